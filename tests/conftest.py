"""Test configuration: float64 (via the tribojax import) and strict rank promotion."""

import jax
import pytest

import tribojax as tj

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_rank_promotion", "raise")

_C = tj.WANG2022_CALIBRATED  # the Table 3 calibration (tribojax's presets, one home)
CALIBRATED = dict(D=_C["D"], G=_C["G_m"], M=_C["M"], mu_t=_C["mu_t"], sigma_s=_C["sigma_s_Pa"])


def make_model(
    D=CALIBRATED["D"], G=CALIBRATED["G"], M=CALIBRATED["M"], mu_t=CALIBRATED["mu_t"],
    sigma_s=CALIBRATED["sigma_s"], **kw,
):  # fmt: skip
    """The wang2022 reticle/chuck contact with Table-3-calibrated constants (tribojax presets)."""
    pair = tj.wang2022_pair(sigma_s=sigma_s)
    kw.setdefault("tangential_load", tj.WANG2022_TANGENTIAL_LOAD_N)
    kw.setdefault("mass", tj.WANG2022_RETICLE_MASS_KG)
    return tj.FractalContact(tj.FractalSurface(D=D, G=G, M=M), pair, mu_t=mu_t, **kw)


@pytest.fixture
def model():
    return make_model()


TABLE3_LOADS = (3.6912, 4.9638, 6.7818, 9.5088, 12.2358, 21.3258)


# --- scheduling over pytest-xdist workers (`--dist loadgroup --no-loadscope-reorder`) -------------
# A test file is one unit of work, so its module fixtures compile once. Files that compile the same
# large programs (equal shapes) share a unit: one worker process, one compile. Units are handed out
# heaviest first (seconds measured on an idle 2-core machine) so that the workers finish together.
SHARED_COMPILE = {
    # discover() on 461-sample slip records: one ~60 s compile of the slip baseline and candidates
    "test_discovery_verdict.py": "slip_discovery",
    "test_cli_discover.py": "slip_discovery",
}
WEIGHT_S = {
    "test_docs.py": 560, "test_reproduce.py": 195, "slip_discovery": 220,
    "test_discovery_slip.py": 75, "test_fit_chain.py": 142, "test_slip.py": 91,
    "test_sensitivity.py": 75, "test_fit_user.py": 59, "test_mhb_excitation.py": 58,
    "test_contact.py": 53, "test_mhb.py": 32, "test_fitting_studies.py": 31, "test_cli_fit.py": 29,
    "test_real_discovery_brfd.py": 25,
}  # the rest: a few seconds each, in file order


def _unit(item) -> str:
    name = item.path.name
    return SHARED_COMPILE.get(name, name)


@pytest.hookimpl(tryfirst=True)  # before xdist's own hook reads the group marks
def pytest_collection_modifyitems(config, items):
    for item in items:
        item.add_marker(pytest.mark.xdist_group(_unit(item)))
    items.sort(key=lambda item: -WEIGHT_S.get(_unit(item), 0.0))  # stable: file order kept

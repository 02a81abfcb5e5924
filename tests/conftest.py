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

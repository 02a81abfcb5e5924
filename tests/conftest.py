"""Test configuration: float64, strict rank promotion, the suite's process choices (a compilation
cache in `build/`, XLA's one-kernel loops as the CLI uses them), shared models, and a count of the
XLA programs each run compiles (printed at the end)."""

import os
from pathlib import Path

# the suite's own choices (the CLI and notebook subprocesses inherit them): one cache for the run,
# and, as the `tribojax` command sets for itself, failures inside diffrax/optimistix/lineax as NaN
os.environ.setdefault("TRIBOJAX_CACHE_DIR", str(Path(__file__).parents[1] / "build" / "jax-cache"))
os.environ.setdefault("EQX_ON_ERROR", "nan")

import jax  # noqa: E402
import pytest  # noqa: E402

import tribojax as tj  # noqa: E402

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_rank_promotion", "raise")
# the suite is an application: it makes the choices the `tribojax` command makes for itself
tj.use_one_kernel()
tj.use_compilation_cache(os.environ["TRIBOJAX_CACHE_DIR"])

_C = tj.WANG2022_CALIBRATED  # the Table 3 calibration (tribojax's presets, one home)
CALIBRATED = dict(D=_C["D"], G=_C["G_m"], M=_C["M"], mu_t=_C["mu_t"], sigma_s=_C["sigma_s_Pa"])
TABLE3_LOADS = (3.6912, 4.9638, 6.7818, 9.5088, 12.2358, 21.3258)


def make_model(
    D=CALIBRATED["D"],
    G=CALIBRATED["G"],
    M=CALIBRATED["M"],
    mu_t=CALIBRATED["mu_t"],
    sigma_s=CALIBRATED["sigma_s"],
    **kw,
):
    """The wang2022 reticle/chuck contact with Table-3-calibrated constants (tribojax presets)."""
    pair = tj.wang2022_pair(sigma_s=sigma_s)
    kw.setdefault("tangential_load", tj.WANG2022_TANGENTIAL_LOAD_N)
    kw.setdefault("mass", tj.WANG2022_RETICLE_MASS_KG)
    return tj.FractalContact(tj.FractalSurface(D=D, G=G, M=M), pair, mu_t=mu_t, **kw)


@pytest.fixture
def model():
    return make_model()


@pytest.fixture
def storable_programs():
    """For tests of values under jit/vmap/grad: the programs they trace hold tribojax's checks as
    NaN (`failures_as_nan`) instead of raising host callbacks, so JAX's persistent cache keeps
    them (a warm run does not compile them again); a failed check shows as a NaN that the test's
    assertions catch. The raising checks under jit are tested on their own (test_checks.py)."""
    from tribojax._checks import failures_as_nan

    with failures_as_nan():
        yield


# --- compiled programs, counted from JAX's monitoring events ----------------------------------
_COUNTS = {"compiled": 0, "from_cache": 0}
_DESELECTED = [0]  # every xdist worker collects (and deselects) the whole suite


def _on_duration(event, duration, **_):
    if event == "/jax/core/compile/backend_compile_duration":
        _COUNTS["compiled"] += 1


def _on_event(event, **_):
    if event == "/jax/compilation_cache/cache_hits":
        _COUNTS["from_cache"] += 1


jax.monitoring.register_event_duration_secs_listener(_on_duration)
jax.monitoring.register_event_listener(_on_event)


def pytest_deselected(items):
    _DESELECTED[0] += len(items)


def pytest_sessionfinish(session):
    if hasattr(session.config, "workeroutput"):  # an xdist worker: report to the controller
        session.config.workeroutput["xla_programs"] = dict(_COUNTS)
        session.config.workeroutput["deselected"] = _DESELECTED[0]


def pytest_testnodedown(node, error):
    output = getattr(node, "workeroutput", {})
    for key, n in output.get("xla_programs", {}).items():
        _COUNTS[key] += n
    _DESELECTED[0] = max(_DESELECTED[0], output.get("deselected", 0))


def pytest_terminal_summary(terminalreporter, config):
    # backend compilations (a persistent-cache hit is not one); in this process and its workers
    terminalreporter.write_line(
        f"XLA programs: {_COUNTS['compiled']} compiled, {_COUNTS['from_cache']} read from the "
        "persistent cache (test processes; CLI and notebook subprocesses not counted)"
    )
    if config.getoption("markexpr") == "not slow":
        terminalreporter.write_line(
            f"fast tier: {_DESELECTED[0]} slow tests not run here; the second tier runs them "
            "(README, 'python -m pytest -m slow'; .ci/run runs both tiers)"
        )

"""Test configuration: float64 (via the tribojax import), strict rank promotion, and the
persistent compilation cache in the build folder (shared by the workers, the CLI and notebook
subprocesses; a clean clone starts it empty)."""

import os
from pathlib import Path

_BUILD = Path(__file__).resolve().parents[1] / "build"
os.environ.setdefault("TRIBOJAX_CACHE_DIR", str(_BUILD / "jax-cache"))

import jax  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import tribojax as tj  # noqa: E402
from tribojax import _checks  # noqa: E402

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_rank_promotion", "raise")

# Checks traced under jit give NaN (tribojax's `failures_as_nan` mode) in every test except those
# marked `raises_inside_jit`: a program with equinox's raising check holds a host callback, which
# JAX 0.10's persistent cache never stores, so it was compiled again on every run (test_contact.py
# 48 -> 19 s warm, test_slip.py 66 -> 35 s). The programs are the same but for the check; a NaN
# cannot pass for a number in the assertions (`assert_allclose` below does not equate NaNs). The
# tests of the raising path (errors inside jit, the CLI's messages) are marked and run as a user's.
_NAN_MODE_ON = _checks._NAN_MODE is not None
if _NAN_MODE_ON:
    jax.config.update("tribojax_failures_as_nan", True)


@pytest.fixture(autouse=True)
def _raising_checks(request):
    """Default (raising) checks for tests marked `raises_inside_jit`."""
    if _NAN_MODE_ON and request.node.get_closest_marker("raises_inside_jit"):
        with _checks._NAN_MODE(False):
            yield
    else:
        yield


_assert_allclose = np.testing.assert_allclose


def _assert_allclose_no_nan(actual, desired, *args, equal_nan=False, **kw):
    return _assert_allclose(actual, desired, *args, equal_nan=equal_nan, **kw)


np.testing.assert_allclose = _assert_allclose_no_nan

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


# --- scheduling over pytest-xdist workers (`--dist loadscope --no-loadscope-reorder`) -------------
# A unit of work is a test file, so its module fixtures compute and compile once; files that compile
# the same large programs (equal shapes) share a unit. Units are handed out heaviest first (seconds
# measured on an idle 2-core machine) so that the workers finish together. The units are the
# scheduler's scopes (`_UnitScheduling`): xdist's `xdist_group` marks do nothing under pytest 9
# (xdist 3.8 renames `item._nodeid`, which pytest 9 no longer reads), which split test_docs.py
# over both workers, so that the site build re-executed a notebook the other one was still running.
SHARED_COMPILE = {
    # discover() on 461-sample slip records: one ~60 s compile of the slip baseline and candidates
    "test_discovery_verdict.py": "slip_discovery",
    "test_cli_discover.py": "slip_discovery",
}
WEIGHT_S = {
    "test_docs.py": 280, "test_fit_chain.py": 100, "slip_discovery": 95, "test_reproduce.py": 76,
    "test_contact.py": 71, "test_slip.py": 56, "test_sensitivity.py": 53,
    "test_discovery_slip.py": 51, "test_fit_user.py": 46, "test_fitting_studies.py": 26,
    "test_mhb_excitation.py": 26, "test_mhb.py": 24, "test_discovery_loop.py": 24,
    "test_cache.py": 26,
}  # the rest: under 20 s each, in file order


def _unit(nodeid: str) -> str:
    name = nodeid.split("::")[0].rsplit("/", 1)[-1]
    return SHARED_COMPILE.get(name, name)


def pytest_collection_modifyitems(config, items):
    items.sort(key=lambda item: -WEIGHT_S.get(_unit(item.nodeid), 0.0))  # stable: file order kept


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    if config.getvalue("dist") != "loadscope":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class _UnitScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid):
            return _unit(nodeid)

        def remove_node(self, node):
            # xdist 3.8 puts every unit of a crashed worker back in the queue, finished ones too;
            # a new worker handed a finished unit runs nothing, nothing asks for the next unit,
            # and the session hangs (a crash near the end ate CI's 5,400 s at stop 41): only
            # units with tests left go back
            work = self.assigned_work.get(node, {})
            for scope in [s for s, unit in work.items() if all(unit.values())]:
                del work[scope]
            return super().remove_node(node)

        def mark_test_pending(self, item):
            # pytest-rerunfailures asks for the test a crashed worker was running once more
            # (LoadScopeScheduling refuses); `remove_node` already queued it unless it ran
            pending = [u for w in (self.workqueue, *self.assigned_work.values())
                       for u in w.values() if u.get(item) is False]  # fmt: skip
            if not pending:
                self.workqueue.setdefault(self._split_scope(item), {})[item] = False
                for node in self.assigned_work:
                    self._reschedule(node)

    return _UnitScheduling(config, log)

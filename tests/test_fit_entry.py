"""One entry point to fit a record, the method as a value (issue 67): `tj.fit(record, method)`
gives what the named shortcut gives, its default is the record's own model (what `tribojax fit`
and `discover`'s baseline fit), and a wrong method or record is refused by name."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import tribojax as tj

SCREW = Path(__file__).resolve().parents[1] / "data" / "real" / "screwdrive"
MU, N, KD, OMEGA = 0.3, 100.0, 2e6, 2 * np.pi * 50


@pytest.fixture(scope="module")
def curve():
    return tj.read_record(SCREW / "driveNo1_steady_0.096kg.csv")


@pytest.fixture(scope="module")
def loop():
    return tj.synthetic_loop(
        tj.Jenkins(MU, N, KD), 3 * MU * N / KD, OMEGA, noise=0.004, seed=4, normal_load=N
    )


def _same(a, b):
    assert a.names == b.names and a.converged and b.converged
    np.testing.assert_array_equal(a.values, b.values)
    np.testing.assert_array_equal(a.std_errors, b.std_errors)


def test_default_is_the_records_own_model(curve, loop):
    _same(tj.fit(curve), tj.fit_record(tj.discovery.curve_baseline(curve)))
    assert tj.fit(curve).names == ("F_c", "sigma2")
    by_default = tj.fit(loop)
    _same(by_default, tj.fit_loop(loop))
    assert by_default.model.kind == "loop"  # the loop record model, not the steady formula
    # within 2 % of the generating μN and K_d (noise 0.4 % of the force)
    assert by_default.values == pytest.approx([MU * N, KD], rel=0.02)


def test_methods_give_their_shortcuts(curve, loop):
    _same(tj.fit(curve, tj.SteadyLaw()), tj.fit_steady_curve(curve))
    _same(tj.fit(curve, tj.SteadyLaw(-1)), tj.fit_steady_curve(curve, direction=-1))
    _same(tj.fit(loop, tj.SteadyLoop("mindlin")), tj.fit_loop(loop, "mindlin", model="steady"))
    history = tj.fit(loop, tj.History("jenkins", decimate=4))
    _same(history.fit, tj.fit_history(loop, "jenkins", decimate=4).fit)
    # a saved model refitted on the record it came from stays where it was
    saved = tj.fitted_model(tj.fit(curve), "driveNo1")
    again = tj.fit(curve, tj.Saved(saved))
    np.testing.assert_allclose(again.values, tj.fit(curve).values, rtol=1e-8)


def test_a_users_method_needs_only_fit(curve):
    @dataclasses.dataclass(frozen=True)
    class Halved(tj.FitMethod):
        def fit(self, record, *, start=None, max_steps=None, throw=True):
            half = dataclasses.replace(record, friction=0.5 * record.friction)
            return tj.fit(half, throw=throw)

    full, half = tj.fit(curve), tj.fit(curve, Halved())
    assert half.values == pytest.approx(0.5 * full.values, rel=1e-6)


def test_wrong_method_or_record_is_refused(curve, tmp_path):
    with pytest.raises(ValueError, match="method must be a tribojax fit method.*str"):
        tj.fit(curve, "lugre")
    with pytest.raises(ValueError, match="start does not apply to a friction curve"):
        tj.fit(curve, start={"F_c": 1.0})
    transient = tj.read_record(SCREW / "driveNo1_start_stop_50.csv")
    with pytest.raises(ValueError, match="not 'friction_transient'.*tj.Transient"):
        tj.fit(transient)
    steady = tj.fit(curve, tj.SteadyLaw())
    dyn = tj.fit(transient, tj.Transient(steady, sigma=float(np.median(curve.friction_scatter))))
    assert dyn.names == ("sigma0", "sigma1") and np.all(dyn.values > 0)

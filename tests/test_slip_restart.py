"""A refit's fresh start (`SlipBaseline.restart`): the slip model's quasi-static start fitted
jointly with the additive columns of the effects in the model. A drift larger than the slip,
read as slip by the baseline's own start, leaves F_s at the bottom of its grid; with the drift
in the model the start finds the stiffness (the run is made by `synthetic_slip_run`, the model's
own simulation: this checks the start rule, not an identification)."""

import dataclasses

import numpy as np
import pytest

import tribojax as tj
from tribojax._model._effects_slip import PositionError, SensorDrift, Vibration

F_S, K_TAU, MASS = 5.77, 1.32e8, 0.321  # the blind record s3007's element (20 kPa)


@pytest.fixture(scope="module")
def drifting():
    el = tj.PreSlipLuGre(F_s=F_S, K_tau=K_TAU, C_tau=994.0)
    run = tj.synthetic_slip_run(el, mass=MASS, n=2301, noise=3e-10, seed=1)
    drift = 4e-9 * (1 - np.exp(-run.t / 0.8))  # thermal, larger than the 2.5 nm peak slip
    return tj.discovery.slip_baseline(dataclasses.replace(run, slip=run.slip + drift))


def test_the_drift_in_the_model_moves_the_start_to_the_element(drifting):
    assert drifting.start_values[0] < 1.1 * MASS  # read as slip: F_s at the grid's bottom
    for design in SensorDrift().designs(drifting):
        theta = drifting.restart((design,))
        assert theta.shape == (3 + design.k,)
        F, K, C = np.asarray(drifting.physical(theta[:3]))
        assert F > 5 * MASS and K == pytest.approx(K_TAU, rel=0.03)
        assert C == pytest.approx(2 * 0.1 * np.sqrt(K * MASS))  # the start rule's C_τ
        # the Legendre amplitudes of the drift (units of the design: the record scale)
        drift = design.basis @ theta[3:]
        assert np.ptp(drift) == pytest.approx(4e-9 * (1 - np.exp(-2.3 / 0.8)), rel=0.1)


def test_no_fresh_start_where_an_effect_moves_the_friction_law(drifting):
    assert drifting.restart(()) is None
    mode = Vibration().design(drifting, 60.0, 0.03)
    assert drifting.restart((SensorDrift().designs(drifting)[0], mode)) is None
    both = (SensorDrift().designs(drifting)[0], PositionError().designs(drifting)[0])
    assert drifting.restart(both).shape == (3 + 4 + 1,)

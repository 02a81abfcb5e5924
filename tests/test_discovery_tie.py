"""A tie between a candidate's grid designs (issue 68 item 2): scores within `SCORE_TIE` of the
best go to the design with fewer parameters, then the earlier grid point, never to the last
bits (the study's s2035: two microslip designs scored 562.53 both)."""

import numpy as np
import pytest

from tribojax._fit._noise import chi2_logsf
from tribojax._model import EffectDesign
from tribojax.discovery._candidates import SCORE_TIE, _tie_first


def _design(k, n_nuisance=0, **nuisance):
    names = tuple(f"s{i}" for i in range(k))
    return EffectDesign(names, ("m",) * k, np.ones(k), nuisance=nuisance, n_nuisance=n_nuisance)


def _scored(entries):
    """(S, dof, design) → the ranking's sorted tuples (log p, −S, grid index, dof, design)."""
    rows = [(chi2_logsf(S, dof), -S, i, dof, d) for i, (S, dof, d) in enumerate(entries)]
    return sorted(rows, key=lambda z: z[:3])


def test_a_tie_goes_to_the_fewer_parameters_whichever_scored_higher():
    shaped, plain = _design(1, 1, shape=1.5), _design(1)
    for eps in (+1e-9, -1e-9):  # the last bits either way: the same design first
        rows = _scored([(562.53 + eps, 1, shaped), (562.53, 1, plain)])
        assert rows[0][4] is (shaped if eps > 0 else plain)  # the sort alone: the last bits
        assert _tie_first(rows)[0][4] is plain


def test_a_tie_between_equal_designs_goes_to_the_earlier_grid_point():
    a, b = _design(2, f_Hz=64.8), _design(2, f_Hz=72.0)
    for eps in (+0.05, -0.05):  # 3e-4 apart on the log p-value: within the tie
        rows = _scored([(214.70, 2, a), (214.70 + eps, 2, b)])
        assert _tie_first(rows)[0][4] is a


@pytest.mark.parametrize("gap", [2.0, 20.0])
def test_a_score_beyond_the_tie_wins_whatever_its_parameters(gap):
    shaped, plain = _design(1, 1, shape=1.5), _design(1)
    S = 562.53
    rows = _scored([(S + gap, 1, shaped), (S, 1, plain)])
    best, second = rows[0][0], rows[1][0]
    assert second > best * (1 - SCORE_TIE)  # outside the tie
    out = _tie_first(rows)
    assert out[0][4] is shaped and [z[4] for z in out] == [shaped, plain]


def test_the_order_is_otherwise_kept_and_nothing_is_lost():
    ds = [_design(1, f_Hz=f) for f in (10.0, 20.0, 30.0, 40.0)]
    rows = _scored([(50.0, 1, ds[0]), (80.0, 1, ds[1]), (79.99, 1, ds[2]), (5.0, 1, ds[3])])
    out = _tie_first(rows)
    assert [z[4] for z in out] == [ds[1], ds[2], ds[0], ds[3]]

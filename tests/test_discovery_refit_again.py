"""A candidate refitted before another one reached the noise gets one more start from that
one's optimum (`discovery._refits.refit_round`; the study's record s1063, a quadratic position
error at 20 kPa whose own starts ran out 3x above the noise while a degree-6 drift reached it);
backward elimination at the noise (`discovery._effect_sets.drop_redundant`); a refit's starts
stop at the noise floor (`_refits._refit`).

The refits are canned: the rules are about which fits are run and which one is kept, not about
a model. Each fit is a stand-in with the attributes the round reads."""

import types

import numpy as np
import pytest

from tribojax.discovery import EffectDesign
from tribojax.discovery import _effect_sets as S
from tribojax.discovery import _refits as R
from tribojax.discovery._candidates import Candidate

N = 400
RNG = np.random.default_rng(0)
NOISE = RNG.normal(size=N)  # white residual: AR(1) ρ ≈ 0, the ΔBIC uninflated


def _design(k):
    return EffectDesign(
        tuple(f"s{i}" for i in range(k)), ("m",) * k, np.ones(k), basis=np.zeros((N, k))
    )


def _fit(rss, theta_b, k, converged=True):
    r = NOISE * np.sqrt(rss / N)
    return types.SimpleNamespace(
        converged=converged,
        rss=rss,
        message="",
        theta=np.concatenate([theta_b, np.zeros(k)]),
        prediction=-r,
    )


class _Run:
    alpha, scale, baseline = 0.05, 1.0, None
    y = np.zeros(N)
    noise = types.SimpleNamespace(sigma=1.0, rho=0.0)  # unit noise, as `consistent` below

    def consistent(self, fit):
        return fit.rss < 1.2 * N  # the noise: RSS of N unit variances

    def prefetch(self, fit):  # a held-out check started early: none here
        pass


@pytest.fixture
def round_(monkeypatch):
    """refit_round over two candidates: `small` (1 strength, refitted first, its own starts
    end at 3x the noise with θ_b = 0) and `big` (7 strengths, reaches the noise with θ_b = 5).
    Returns a function giving (accepted, state, small candidate, fits run from big's θ_b)."""
    from_big = []

    def refit(baseline, state, design, name, *args):
        return _fit(3.0 * N, [0.0], design.k) if name == "small" else _fit(N, [5.0], design.k)

    def fit_model(baseline, designs, x0, y, scale, names, max_steps, abandon_above):
        from_big.append((names[-1], x0[0], max_steps, abandon_above))
        return _fit(small_again, [x0[0]], designs[-1].k)

    monkeypatch.setattr(R, "_refit", refit)
    monkeypatch.setattr(R, "fit_model", fit_model)
    monkeypatch.setattr(R, "_strengths_of", lambda run, fit, name: {})
    effect = types.SimpleNamespace(reject=lambda strengths: None)
    small_again = N

    def go(again_rss, big_k=7):
        nonlocal small_again
        small_again = again_rss
        cands = [
            Candidate("small", 50.0, 1, 1e-10, 1, _design(1), [], True),
            Candidate("big", 40.0, big_k, 1e-8, 1, _design(big_k), [], True),
        ]
        ranking = types.SimpleNamespace(candidates=cands, residual=None, cache=None)
        state = types.SimpleNamespace(rss=10.0 * N, theta=np.zeros(1), designs=(), effects=())
        accepted = R.refit_round(
            _Run(), state, ranking, 4, -10.0, {"small": effect, "big": effect}, False
        )
        return accepted, state, cands[0], from_big

    return go


def test_a_smaller_candidate_is_refitted_from_the_optimum_that_reaches_the_noise(round_):
    accepted, state, small, runs = round_(0.99 * N)
    # once, from big's θ_b, quick budget, abandoned while above the margin over big's cost
    assert runs == [("small", 5.0, R.QUICK_STEPS, R.QUICK_MARGIN * N)]
    assert small.refit[0].rss == pytest.approx(0.99 * N)
    assert small.refit_message == R._AGAIN
    assert [a[0].name for a in accepted] == ["big", "small"]
    # at the noise with 1 strength against 7: the choice goes to the small one
    assert R.choose(accepted, state, N)[0] is small


def test_the_new_start_is_kept_only_where_it_is_better(round_):
    accepted, state, small, runs = round_(5.0 * N)  # worse than its own refit (3x)
    assert len(runs) == 1
    assert small.refit[0].rss == pytest.approx(3.0 * N)
    assert small.refit_message != R._AGAIN
    assert R.choose(accepted, state, N)[0].name == "big"


def test_no_new_start_for_a_candidate_with_as_many_parameters(round_):
    _, _, small, runs = round_(0.99 * N, big_k=1)
    assert runs == []
    assert small.refit[0].rss == pytest.approx(3.0 * N)


# backward elimination (`drop_redundant`): the study's record s1045, where `viscous_friction`
# was added before `stribeck`, which then took the misfit to the noise alone


def _state(rss, effects, ks):
    f = _fit(rss, [0.0], sum(ks))
    f.effects, f.designs = tuple(effects), tuple(_design(k) for k in ks)
    return f


@pytest.fixture
def drop(monkeypatch):
    """drop_redundant on a model of effects ("a", "b", "c") with 1, 2, 1 strengths at the noise;
    `without[name]`: the RSS of the model refitted without that effect (any other: 3x noise)."""
    tried = []

    def fit_model(baseline, designs, x0, y, scale, names):
        gone = "".join(sorted({"a", "b", "c"} - set(names)))
        tried.append(gone)
        return _state(go.without.get(gone, 3.0 * N), names, [d.k for d in designs])

    monkeypatch.setattr(S, "fit_model", fit_model)
    run = _Run()
    run.consistent = lambda fit: fit.rss < 1.03 * N  # a tighter noise test than _Run's
    run.baseline = types.SimpleNamespace(param_names=("A",))

    def go(without, effects=("a", "b", "c"), ks=(1, 2, 1)):
        go.without = without
        tried.clear()
        state, dropped = S.drop_redundant(run, _state(N, effects, ks), -10.0)
        return state.effects, dropped, list(tried)

    return go


def test_an_earlier_effect_that_no_longer_earns_its_place_is_dropped(drop):
    effects, dropped, tried = drop({"a": 1.001 * N, "b": 3.0 * N, "c": 3.0 * N})
    assert dropped == ["a"] and effects == ("b", "c")
    assert "c" not in tried  # the last one added earned its place against the model before it
    assert tried == ["a", "b", "ab"]  # then (b, c) without b: 3x the noise, kept


def test_effects_that_earn_their_place_are_kept(drop):
    # dropping `a` raises the RSS by 10 %: ΔBIC = N ln(1/1.1) + ln N ≈ -32 < -10
    effects, dropped, _ = drop({"a": 1.1 * N, "b": 3.0 * N, "c": 3.0 * N})
    assert dropped == [] and effects == ("a", "b", "c")


def test_no_drop_that_leaves_the_noise(drop):
    # ΔBIC alone drops `b` (2 strengths for 4 % of the RSS: ΔBIC ≈ -15.7 + 12 > -10), but the
    # model without it is no longer consistent with the noise (RSS < 1.03 N) where the full was
    effects, dropped, _ = drop({"a": 3.0 * N, "b": 1.04 * N, "c": 3.0 * N})
    assert dropped == []
    effects, dropped, _ = drop({"a": 3.0 * N, "b": 1.02 * N, "c": 3.0 * N})
    assert dropped == ["b"]


def test_a_single_effect_is_never_tested(drop):
    effects, dropped, tried = drop({"a": N}, effects=("a",), ks=(1,))
    assert effects == ("a",) and dropped == [] and tried == []


def test_no_elimination_where_a_misfit_is_left(drop, monkeypatch):
    # the blind band brake: at "partly explained" the AR(1)-inflated ΔBIC dropped a real effect
    monkeypatch.setattr(S, "_delta_bic", lambda *a: 0.0)  # any drop would pass the ΔBIC test
    run = _Run()
    run.baseline = types.SimpleNamespace(param_names=("A",))
    state, dropped = S.drop_redundant(run, _state(2.0 * N, ("a", "b"), (1, 1)), -10.0)
    assert dropped == [] and state.effects == ("a", "b")


def _refit_with(monkeypatch, gn_rss, gn_converged=True, target=None):
    """_refit of a 1-strength design with two starts, the current cost 10 N, the noise floor
    1.1 N; the Gauss–Newton start ends at `gn_rss`, every other start at 1.1 N. Returns the
    kept fit and the (x0, ceiling, abandon_above, max_steps) of each fit run, in order."""
    calls = []

    def fit_model(baseline, designs, x0, y, scale, names, max_steps, ceiling, abandon_above):
        calls.append((float(x0[-1]), ceiling, abandon_above, max_steps))
        first = len(calls) == 1
        return types.SimpleNamespace(
            converged=gn_converged or not first,
            steps=5,
            theta=x0,
            rss=gn_rss if first else 1.1 * N,
            message="",
            gain_left=0.0,  # at a minimum: no restart around the stop (`restarted_around`)
        )

    monkeypatch.setattr(R, "fit_model", fit_model)
    monkeypatch.setattr(R, "_columns", lambda baseline, state, design, cache: np.ones((N, 1)))
    state = types.SimpleNamespace(
        theta=np.zeros(1), jacobian=RNG.normal(size=(N, 1)), rss=10.0 * N, designs=(), effects=()
    )
    design = types.SimpleNamespace(k=1, starts=((10.0,), (100.0,)))
    fit = R._refit(
        None, state, design, "x", np.zeros(N), 1.0, NOISE, None, target=target, floor=1.1 * N
    )
    return fit, sorted(calls[1:], key=repr), calls[0]


@pytest.mark.parametrize("gn_rss, runs", [(1.0 * N, 1), (1.2 * N, 3)])
def test_starts_stop_once_the_gauss_newton_start_is_at_the_noise(monkeypatch, gn_rss, runs):
    # _refit: the Gauss–Newton start runs first; converged at or below the noise floor (here
    # 1.1 N) it is kept alone; above it the design's two starts run and the lowest cost is kept
    fit, others, first = _refit_with(monkeypatch, gn_rss)
    assert 1 + len(others) == runs and fit.rss == min(gn_rss, 1.1 * N)
    # each start's ceiling (no restart above it) and abandon bar: the current cost
    assert {c[1:3] for c in [first, *others]} == {(10.0 * N, 10.0 * N)}
    assert [c[0] for c in others] == [10.0, 100.0][: runs - 1]


def test_the_zero_start_is_never_abandoned_at_the_current_cost(monkeypatch):
    # the Gauss–Newton start failed: the zero start (strength 0) runs too; it begins at the
    # current cost, so it has no abandon bar, while the design's starts have the current cost
    fit, others, _ = _refit_with(monkeypatch, 20.0 * N, gn_converged=False)
    assert [c[0] for c in others] == [0.0, 10.0, 100.0]
    assert [c[2] for c in others] == [np.inf, 10.0 * N, 10.0 * N]
    assert fit.rss == 1.1 * N


def test_a_quick_refit_is_abandoned_above_the_margin_over_the_target(monkeypatch):
    # another candidate reached RSS 1.0 N: each start has QUICK_STEPS steps and is abandoned
    # above QUICK_MARGIN × 1.0 N; the zero start (at 10 N, beyond that margin) is not run
    _, others, first = _refit_with(monkeypatch, 20.0 * N, gn_converged=False, target=1.0 * N)
    assert first[2:] == (R.QUICK_MARGIN * N, R.QUICK_STEPS)
    assert [c[0] for c in others] == [10.0, 100.0]
    assert all(c[2:] == (R.QUICK_MARGIN * N, R.QUICK_STEPS) for c in others)


def test_noise_floor_is_one_spread_above_the_noise():
    run = _Run()
    run.noise = types.SimpleNamespace(sigma=2.0, rho=0.0)
    state = types.SimpleNamespace(theta=np.zeros(3))
    m = N - 3 - 2
    assert R._noise_floor(run, state, _design(2)) == pytest.approx(4.0 * (m + np.sqrt(2 * m)))
    run.noise.rho = 0.5  # AR(1): the sum of squares spreads by √((1 + ρ²)/(1 − ρ²))
    assert R._noise_floor(run, state, _design(2)) == pytest.approx(
        4.0 * (m + np.sqrt(2 * m * 1.25 / 0.75))
    )

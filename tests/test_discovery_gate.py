"""Issue 68: the held-out gate and the verdict never contradict their own statistics.

A misfit within the noise's mean square (here: a stated noise sd twice the true one, the misfit
local to the reversals) has an excess over the noise of 0, yet the noise test finds it. The
held-out gate compares held-out mean squares, so the right effect is added; the verdict follows.
The record is made by `tests/blind_gate/generate_loops.py`, written without the library's code.
"""

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from tribojax._cli import main
from tribojax.discovery._verdict import HELDOUT_TIE, verdict

_GEN = Path(__file__).resolve().parent / "blind_gate" / "generate_loops.py"


def _generator():
    spec = importlib.util.spec_from_file_location("blind_generate_loops", _GEN)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_misfit_within_the_noise_mean_square_is_found_and_explained(tmp_path, capsys):
    csv = _generator().write_record(tmp_path, "partial_slip", 1, delta_star=3e-6, sigma_N=1.0)
    side = csv.with_suffix(".json")
    meta = json.loads(side.read_text())
    meta["noise_std_N"] = 2.0  # a conservative user: twice the true 1 N
    side.write_text(json.dumps(meta))
    out = tmp_path / "d"
    assert main(["discover", str(csv), "--out", str(out)]) == 0
    d = json.loads((out / "discovery.json").read_text())
    m = d["misfit"]
    assert not m["baseline_consistent"]  # the test finds the misfit ...
    assert d["excess_rmse_before"] == 0.0  # ... which is within the noise's mean square
    ev = m["baseline_evidence"]
    assert min(ev["periodic_line_p"], ev["whole_record_p"]) < 1e-6 or ev["windows_flagged"] > 0
    assert d["effects"] == ["microslip"] and d["verdict"] == "explained"
    before, after = m["heldout_rms"]
    assert after < 0.8 * before  # what the gate compared: the held-out mean square fell
    said = capsys.readouterr().out
    assert "found by the noise test" in said and "(rms " in said


@pytest.mark.parametrize(
    "ms, expected",
    [
        ((4.0, 1.0), "explained"),  # h₀ = 0: the held-out mean square stands for "halved"
        ((4.0, 4.0 * (1 - 0.5 * HELDOUT_TIE)), "unexplained"),  # a tie: not lowered
    ],
)
def test_verdict_compares_heldout_mean_squares_where_the_excess_is_zero(ms, expected):
    v = verdict(1, False, True, 0.0, 0.0, (0.0, 0.0), sigma=2.0, heldout_ms=ms)
    assert v == expected
    # the rule before issue 68 ("halved" needs h₀ > 0) called both "unexplained"
    assert verdict(1, False, True, 0.0, 0.0, (0.0, 0.0), sigma=2.0) == "unexplained"


def test_verdict_unchanged_where_the_heldout_excess_is_positive():
    # h₀ > 0: the held-out mean squares order the models as the excesses do
    sig = 1.0
    for h, ms, want in [
        ((2.0, 0.5), (5.0, 1.25), "explained"),
        ((2.0, 1.5), (5.0, 3.25), "partly_explained"),  # held out lowered, not halved
    ]:
        assert verdict(1, False, True, 1.0, 0.0, h, sigma=sig, heldout_ms=ms) == want
        assert verdict(1, False, True, 1.0, 0.0, h, sigma=sig) == want


def test_a_tie_in_the_choice_goes_to_fewer_parameters_then_the_name():
    # issue 68: two refits at the same cost to the last bits (loop s2035: microslip and backlash,
    # ΔBIC −94.197905263078 both) are chosen by a stated rule, not by their last bits
    import types

    from tribojax.discovery import _refits as R
    from tribojax.discovery._verdict import BIC_TIE

    n, rss0 = 1000, 1000.0
    state = types.SimpleNamespace(rss=rss0)

    def cand(name, rss, dk):
        return (types.SimpleNamespace(name=name), types.SimpleNamespace(rss=rss), dk, 1.0)

    for order in (1, -1):  # either order, either last bit
        a = [cand("zeta", 500.0 * (1 - 1e-15), 1), cand("alpha", 500.0, 1)][::order]
        assert R.choose(a, state, n)[0].name == "alpha"  # same parameters: by name
        b = [cand("alpha", 500.0 * (1 - 1e-15), 2), cand("zeta", 500.0, 1)][::order]
        assert R.choose(b, state, n)[0].name == "zeta"  # fewer parameters first
    # beyond the tie band the lower ΔBIC wins, whatever its name
    far = 500.0 * float(np.exp(-4 * BIC_TIE / n))  # ΔBIC lower by 4 BIC_TIE
    c = [cand("alpha", 500.0, 1), cand("zeta", far, 1)]
    assert R.choose(c, state, n)[0].name == "zeta"
    assert c[1][0].delta_bic_common < c[0][0].delta_bic_common - 3 * BIC_TIE

"""Discovery on measured friction-damper (brfd) records: the study's rows on short excerpts.

The damper is a self-energizing band brake with a clearance at motion reversal: `backlash` (on
records without a band tension, where the band's effects are no candidates) or the band's
`self_energizing` rise must lead the ranking on its records.
"""

import dataclasses
from pathlib import Path

import pytest
from fitting.real_discovery_brfd import brfd_files, discover_brfd_test, physical_sense

import tribojax as tj

pytestmark = pytest.mark.slow  # the second tier (tests/conftest.py)

ROOT = Path(__file__).resolve().parents[1]
BUNDLED = ROOT / "data" / "real" / "brfd" / "2Hz30lbtension0.5amplitude.csv"
SHARED = ROOT.parent / "shared" / "data" / "real" / "brfd" / "0.25Hz30lbtension0.5amplitude.json"


def _excerpt(loop, t0, t1):
    keep = (loop.t >= t0) & (loop.t <= t1)
    return dataclasses.replace(loop, t=loop.t[keep], u=loop.u[keep], f=loop.f[keep])


def test_bundled_excerpt_ranks_backlash_first():
    """3½ steady cycles of the bundled 2 Hz test (blocks of 4: 435 samples). At 2 Hz the ringing
    after each re-engagement dominates the misfit, so nothing passes ΔBIC, but the clearance is
    the strongest signal: first by score."""
    loop = _excerpt(tj.read_record(BUNDLED), 0.9, 2.6)
    row = discover_brfd_test(BUNDLED, record=loop, factor=4)
    assert row["first_round"][0]["name"] == "backlash"
    assert row["first_round"][0]["p_value"] < 1e-10
    # no candidate lowers the BIC (the ringing is no candidate's shape: backlash ΔBIC +5.4), so
    # nothing is added and the misfit of several kN (μN ≈ 10 kN) stays, far above the noise:
    # unexplained, with the misfit flagged over the whole excerpt
    assert row["converged"] and row["effects"] == [] and row["verdict"] == "unexplained"
    assert row["drive"] == "sinusoidal" and row["frequency_Hz"] == 2.0
    assert row["excess_rmse_after_N"] == row["excess_rmse_before_N"] > 1e3
    assert row["misfit"]["regions"] and row["misfit"]["share_of_samples"] > 0.9
    assert row["physical_sense"].startswith("nothing named: backlash was expected")


@pytest.mark.skipif(not SHARED.exists(), reason="../shared/data/real (full brfd data) absent")
def test_shared_excerpt_names_the_band_brake():
    """Two steady cycles of the 0.25 Hz, 0.5 in test (blocks of 16: 524 samples). The record
    carries its band tension (30 lb, from the file name), so the band brake's effects are
    candidates: the capstan rise is named first (ΔBIC −32, backlash −24 in the same round), then
    the direction asymmetry, a ≈ 0.13 (the band-brake element fitted on all ten sines has
    (F₊ − F₋)/(F₊ + F₋) = 0.14); the excess misfit goes from 2.2 kN to 0.67 kN (with backlash and
    a force offset, the vocabulary without the band's effects: 0.9 kN), still far above the
    noise over most of the loop: partly_explained."""
    loop = _excerpt(tj.read_record(SHARED), 8.0, 16.2)
    assert loop.band_tension == pytest.approx(30 * 4.4482216152605)
    row = discover_brfd_test(SHARED, record=loop, factor=16)
    assert row["effects"][:2] == ["self_energizing", "direction_asymmetry"]
    assert [c["name"] for c in row["first_round"][:2]] == ["self_energizing", "backlash"]
    assert 0.08 < row["strengths"]["direction_asymmetry"]["a"]["value"] < 0.18
    assert row["strengths"]["self_energizing"]["sigma"]["value"] > 0.5
    assert row["excess_rmse_after_N"] < 0.35 * row["excess_rmse_before_N"]
    assert row["verdict"] == "partly_explained" and row["misfit"]["share_of_samples"] > 0.5
    assert row["physical_sense"].startswith("self_energizing: the band's capstan rise")


def test_files_and_notes():
    assert brfd_files(ROOT / "no-such-folder") == sorted((BUNDLED.parent).glob("*.csv"))
    assert physical_sense([]).startswith("nothing named")
    assert physical_sense(["force_offset"]).startswith("neither backlash nor the band's rise")
    assert physical_sense(["backlash", "force_offset"]).startswith("backlash: expected")

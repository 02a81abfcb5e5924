"""Discovery on measured friction-damper (brfd) records: the study's rows on short excerpts.

The damper has a clearance at motion reversal; `backlash` must lead the ranking on its records.
"""

import dataclasses
from pathlib import Path

import pytest
from fitting.real_discovery_brfd import brfd_files, discover_brfd_test, physical_sense

import tribojax as tj

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
def test_shared_excerpt_names_backlash():
    """Two steady cycles of the 0.25 Hz, 0.5 in test (blocks of 16: 524 samples): backlash is
    named first, with the gap seen in the loops (a zero-force plateau of about 5 mm)."""
    loop = _excerpt(tj.read_record(SHARED), 8.0, 16.2)
    row = discover_brfd_test(SHARED, record=loop, factor=16)
    # backlash first (ΔBIC −23), then a force offset (ΔBIC −32 in the second round: the two
    # directions' friction differs); they take the excess misfit from 2.2 kN to 0.9 kN, more
    # than halved, but it stays far above the noise over most of the loop: partly_explained
    assert row["effects"] == ["backlash", "force_offset"]
    assert 4.0 < row["backlash_gap_mm"] < 6.5
    assert row["backlash_depth"] > 0.8
    assert row["excess_rmse_after_N"] < 0.5 * row["excess_rmse_before_N"]
    assert row["verdict"] == "partly_explained" and row["misfit"]["share_of_samples"] > 0.5


def test_files_and_notes():
    assert brfd_files(ROOT / "no-such-folder") == sorted((BUNDLED.parent).glob("*.csv"))
    assert physical_sense([]).startswith("nothing named")
    assert physical_sense(["force_offset"]).startswith("backlash not named first")

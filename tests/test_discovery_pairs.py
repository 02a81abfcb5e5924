"""Two effects at once (`tribojax.discovery._effect_sets.pair_round`, issue 32): when no single
candidate qualifies because the misfit a second effect leaves correlates the residual (its AR(1)
inflation near the bound), the best single refits are fitted jointly in pairs.

The record is the blind generator's s5014 (benchmarks/blind/, written from a physical brief only):
a normal load varying along the stroke and a clearance. It was examined while writing the pair
step, so here it is a regression case, not blind evidence (the fresh batch of
benchmarks/blind_pairs.py is, docs/discovery.md)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

import tribojax as tj
import tribojax.discovery as disc

BLIND = Path(__file__).resolve().parents[1] / "benchmarks" / "blind"
LABEL = "loop/normal_load_variation+backlash/sine/muN400N/s5014"


@pytest.mark.slow
def test_a_load_variation_and_a_clearance_are_named_together(tmp_path):
    subprocess.run(
        [
            sys.executable,
            str(BLIND / "generate.py"),
            "--out",
            str(tmp_path),
            "--quiet",
            "--only",
            LABEL,
        ],
        check=True,
    )
    (entry,) = json.loads((tmp_path / "manifest.json").read_text())
    truth = entry["params"]["effects"]
    rep = disc.discover(disc.loop_baseline(tj.read_record(tmp_path / entry["file"])))
    first = {c["name"]: c for c in rep.rounds[0]}
    # neither alone earns its place (the stop-51 answer was "unexplained", nothing added) ...
    for name in ("normal_load_variation", "backlash"):
        assert first[name]["delta_bic"] > disc.DELTA_BIC_THRESHOLD
        assert first[name]["refit_message"].startswith("added with ")
    # ... together both are named, nothing else, and the misfit goes, held out too
    assert sorted(rep.effects) == ["backlash", "normal_load_variation"]
    assert rep.excess_rmse_after < 0.05 * rep.excess_rmse_before
    assert rep.heldout_excess_after < 0.05 * rep.heldout_excess_before
    beta = rep.strengths["normal_load_variation"]["beta"]
    assert abs(beta["value"] - truth["normal_load_variation"]["beta"]) < 0.01
    gap = rep.strengths["backlash"]["nuisance"]["gap_m"]
    assert abs(gap / truth["backlash"]["gap_m"] - 1) < 0.05

"""Discovery on records of a band brake written blind (benchmarks/blind/band_brake_generator.py:
a helper given only a physical description — a capstan band with a clearance, a compliant stop
and a self-energizing direction — and NumPy; it never saw the loop model or its effects).

    python -m benchmarks.experiments.blind_band_brake_discovery [RECORDS_DIR]

Discovery runs on the 1 Hz sine (with the band tension, so the band's effects are candidates,
and without it: the vocabulary before them); each discovered model, and the Jenkins baseline,
then predicts the generator's two-tone history, which no fit saw. Prints one JSON object."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

import tribojax as tj
from tribojax.discovery import discover_loop

HERE = Path(__file__).resolve().parents[1] / "blind" / "band_brake"
TENSION_N = 30 * 4.4482216152605  # the generator's set tension, 30 lbf


def _loop(path: Path, periodic: bool, tension=None) -> tj.HysteresisLoop:
    d = np.genfromtxt(path, delimiter=",", names=True)
    return tj.HysteresisLoop(
        t=d["time_s"],
        u=d["displacement_m"],
        f=d["force_N"],
        periodic=periodic,
        band_tension=tension,
    )


def main(folder: Path = HERE) -> dict:
    other = _loop(folder / "history.csv", periodic=False)
    out = {}
    for name, tension in (("with the band's effects", TENSION_N), ("without", None)):
        rep = discover_loop(_loop(folder / "sine_1Hz.csv", True, tension))
        out[name] = {
            "effects": list(rep.effects),
            "verdict": rep.verdict,
            "strengths": rep.as_dict()["strengths"],
            "noise_std": rep.noise_std,
            "excess_before": rep.excess_rmse_before,
            "excess_after": rep.excess_rmse_after,
            "heldout_excess_before": rep.heldout_excess_before,
            "heldout_excess_after": rep.heldout_excess_after,
            "history_nrmse": tj.predict(rep.fitted, other).nrmse,
        }
    base = discover_loop(_loop(folder / "sine_1Hz.csv", True), effects=[], max_effects=0)
    out["jenkins baseline"] = {"history_nrmse": tj.predict(base.fitted, other).nrmse}
    return out


if __name__ == "__main__":
    print(
        json.dumps(main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE), indent=1, default=float)
    )

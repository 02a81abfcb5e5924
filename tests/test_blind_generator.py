"""The blind generator of issue 32 (benchmarks/blind/, written from the papers and a physical
brief only, never from the candidate code) is frozen: its code hashes to what was stored when it
was frozen, its records match the hashes stored then (FROZEN.sha256) — or, where a CPU's
floating-point differs in the last digits (SciPy LSODA's slip runs), the stored values to 1e-7 of
each column's scale (FROZEN_VALUES.json) — and they are files tribojax reads as a user's records."""

import hashlib
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

import tribojax as tj

BLIND = Path(__file__).resolve().parents[1] / "benchmarks" / "blind"
# one slip run with two hidden effects, one loop under a non-sinusoidal drive
LABELS = ("slip/sensor_drift+vibration/trapezoid/10kPa/s3025", "loop/backlash/sine3/muN400N/s5009")


def test_blind_records_are_the_frozen_ones(tmp_path):
    rows = (line.split() for line in (BLIND / "FROZEN.sha256").read_text().splitlines())
    frozen = {name: digest for digest, name in rows}
    values = json.loads((BLIND / "FROZEN_VALUES.json").read_text())
    for name, digest in values["code_sha256"].items():
        assert hashlib.sha256((BLIND / name).read_bytes()).hexdigest() == digest, f"{name} changed"
    assert len(frozen) == 2 * 45 + 1  # 29 slip runs, 16 loops (CSV + sidecar), the manifest
    subprocess.run(
        [
            sys.executable,
            str(BLIND / "generate.py"),
            "--out",
            str(tmp_path),
            "--quiet",
            "--only",
            *LABELS,
        ],
        check=True,
    )
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert sorted(e["label"] for e in manifest) == sorted(LABELS)
    for entry in manifest:
        stem = Path(entry["file"]).stem
        for suffix in (".csv", ".json"):
            digest = hashlib.sha256((tmp_path / f"{stem}{suffix}").read_bytes()).hexdigest()
            if digest == frozen[f"{stem}{suffix}"]:
                continue
            assert suffix == ".csv", f"{stem}{suffix} changed"
            got = np.loadtxt(tmp_path / f"{stem}.csv", delimiter=",", skiprows=2)[::25]
            want = np.asarray(values["rows"][f"{stem}.csv"])
            assert got.shape == want.shape, f"{stem}.csv changed length"
            scale = np.max(np.abs(want), axis=0)
            assert np.all(np.abs(got - want) <= 1e-7 * scale), f"{stem}.csv changed"
        record = tj.read_record(tmp_path / entry["file"])
        assert record.kind == {"slip": "slip_run", "loop": "loop"}[entry["kind"]]
        assert entry["hidden"] and min(entry["visibility_sd"].values()) >= 3.0

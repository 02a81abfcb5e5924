"""The blind generator of issue 32 (benchmarks/blind/, written from the papers and a physical
brief only, never from the candidate code) is frozen: its records are byte-identical to the
hashes stored when it was frozen (FROZEN.sha256), and they are files tribojax reads as a user's
records."""

import hashlib
import json
import subprocess
import sys
from pathlib import Path

import tribojax as tj

BLIND = Path(__file__).resolve().parents[1] / "benchmarks" / "blind"
# one slip run with two hidden effects, one loop under a non-sinusoidal drive
LABELS = ("slip/sensor_drift+vibration/trapezoid/10kPa/s3025", "loop/backlash/sine3/muN400N/s5009")


def test_blind_records_are_the_frozen_ones(tmp_path):
    rows = (line.split() for line in (BLIND / "FROZEN.sha256").read_text().splitlines())
    frozen = {name: digest for digest, name in rows}
    assert len(frozen) == 2 * 45 + 1  # 29 slip runs, 16 loops (CSV + sidecar), the manifest
    subprocess.run([sys.executable, str(BLIND / "generate.py"), "--out", str(tmp_path), "--quiet",
                    "--only", *LABELS], check=True)  # fmt: skip
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert sorted(e["label"] for e in manifest) == sorted(LABELS)
    for entry in manifest:
        stem = Path(entry["file"]).stem
        for suffix in (".csv", ".json"):
            digest = hashlib.sha256((tmp_path / f"{stem}{suffix}").read_bytes()).hexdigest()
            assert digest == frozen[f"{stem}{suffix}"], f"{stem}{suffix} changed"
        record = tj.read_record(tmp_path / entry["file"])
        assert record.kind == {"slip": "slip_run", "loop": "loop"}[entry["kind"]]
        assert entry["hidden"] and min(entry["visibility_sd"].values()) >= 3.0

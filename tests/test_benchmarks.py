"""The benchmark harness cannot rot unnoticed (issue 31 item 6), without timing anything.

`python benchmarks/run.py --quick --out DIR` takes about 13 minutes on 2 cores, too long for this
suite; here every benchmark module is imported, the summary table is printed for entries with
and without a baseline, and the cold-start probe runs a cheap command through it.
"""

import importlib
import json
import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
MODULES = sorted(p.stem for p in BENCH.glob("*.py") if p.stem not in ("__init__",))


@pytest.fixture(autouse=True)
def _on_path(monkeypatch):
    monkeypatch.syspath_prepend(str(BENCH))


@pytest.mark.parametrize("name", MODULES)
def test_benchmark_module_imports(name):
    module = importlib.import_module(name)
    assert module.__doc__, f"benchmarks/{name}.py has no docstring"


def test_summary_table_prints_entries_without_a_baseline(capsys):
    run = importlib.import_module("run")
    env = {"python": "3.11"}
    entries = [
        dict(
            name="with_baseline",
            tribojax_s=0.5,
            baseline="scipy",
            baseline_s=1.0,
            ratio=2.0,
            target=1.0,
            meets_target=True,
            environment=env,
        ),
        dict(
            name="fit_slip_run_alpha_fixed",
            tribojax_s=2e-4,
            baseline=None,
            baseline_s=None,
            ratio=None,
            target=None,
            meets_target=None,
            environment=env,
        ),
    ]
    run.print_table(entries, 1.0)
    text = capsys.readouterr().out
    assert "fit_slip_run_alpha_fixed" in text and "200.0 us" in text and "no baseline" in text
    assert "2" in text.splitlines()[1]


@pytest.mark.slow
def test_cold_start_probe_splits_a_command(tmp_path):
    cold = importlib.import_module("cold_start")
    argv = ["contact", "--D", "2.88", "--G", "4.36e-8", "--load", "5"]
    out = subprocess.run(
        [sys.executable, "-c", cold._PROBE, json.dumps(argv)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=300,
    )
    split = cold._last(out, "SPLIT")
    assert split["exit"] == 0, out.stderr[-2000:]
    parts = ("import_s", "trace_s", "lower_s", "compile_s")
    assert all(0 <= split[k] <= split["total_s"] for k in parts) and split["programs"] > 0
    # start-up ends with the first traced program, so it overlaps the trace a little
    assert split["import_s"] + split["lower_s"] + split["compile_s"] <= split["total_s"] + 1e-6

"""Benchmark: `tribojax fit` and `tribojax discover` on records of 10^6 samples (issue 18, point 4).

Records (made here, seeded, written to a scratch folder):
* slip: `synthetic_slip_run` of wang2022 Table 3's 0.6 kPa element over its 2.3 s cycle at
  1,000,041 samples (2.3 µs, a spacing that divides the trapezoid's 5 ms corners), noise 2e-10 m,
  seed 7;
* loop: `synthetic_loop` of a Jenkins element (μ 0.3, N 2.94 N, K_d 1.2e6 N/m, Ā = 3) at 22 Hz
  sampled at 455 samples per cycle (10 kHz) for 2198 cycles (100 s, 1,000,204 samples), force
  noise 0.004 N, seed 4.

Each command runs in a fresh process (compilation included, as a user meets it); wall time and
peak RSS (the child's own `resource.getrusage(RUSAGE_SELF)` at exit) are recorded, with the
fit's parameters against the truth in standard errors. Targets: ≤ 60 s and ≤ 2 GiB on 2 cores.
The baseline is the same command with `--decimate off` (every sample), where affordable
(`--with-baseline`): on 10^6
samples it is the issue's "did not finish" case, so it runs under a time limit.

    python benchmarks/long_records.py [--out DIR] [--with-baseline] [--only NAME ...]
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import tribojax as tj

SLIP_TRUTH = {"F_s": 0.4868, "K_tau": 1.4878e7, "C_tau": 771.05}
SLIP_N = 460 * 2174 + 1  # 1,000,041: the spacing 2.3 s / 1,000,040 divides 5 ms
MU, N_LOAD, KD, F_HZ = 0.3, 2.94, 1.2e6, 22.0
LOOP_CYCLES, LOOP_PER_CYCLE = 2198, 455
TIME_LIMIT_S = 600


def make_records(folder: Path) -> dict:
    folder.mkdir(parents=True, exist_ok=True)
    paths = {"slip": folder / "slip_1e6.csv", "loop": folder / "loop_1e6.csv"}
    if not paths["slip"].exists():
        el = tj.PreSlipLuGre(*SLIP_TRUTH.values(), 1.0)
        run = tj.synthetic_slip_run(el, noise=2e-10, seed=7, n=SLIP_N, t_end=2.3)
        tj.write_slip_run(run, paths["slip"])
    if not paths["loop"].exists():
        omega = 2 * np.pi * F_HZ
        loop = tj.synthetic_loop(
            tj.Jenkins(MU, N_LOAD, KD),
            3 * MU * N_LOAD / KD,
            omega,
            cycles=LOOP_CYCLES,
            samples_per_cycle=LOOP_PER_CYCLE,
            noise=0.004,
            seed=4,
            normal_load=N_LOAD,
        )
        tj.write_loop(loop, paths["loop"])
    return paths


def run_cli(args: list[str], limit: float = TIME_LIMIT_S) -> dict:
    """Run `tribojax ARGS` in a fresh process: wall time, its peak RSS (GiB, the child's own
    rusage from `os.wait4`: the console script ends with `os._exit`, so no handler of its own
    could report it), exit status. Past `limit` s the child is killed (exit None)."""
    code = (
        "import sys; from importlib.metadata import entry_points; "
        "(script,) = entry_points(group='console_scripts', name='tribojax'); "
        "sys.exit(script.load()())"
    )
    t0 = time.perf_counter()
    with tempfile.TemporaryFile("w+") as log:
        proc = subprocess.Popen(
            [sys.executable, "-c", code, *args], stdout=log, stderr=subprocess.STDOUT, text=True
        )
        pid, status, usage = 0, 0, None
        while time.perf_counter() - t0 < limit:  # (wait4, not poll: poll would reap it first)
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            time.sleep(0.05)
        if not pid:
            proc.kill()
            os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status) if pid else -9
        log.seek(0)
        tail = log.read()[-1500:]
    if not pid:
        return {
            "wall_s": wall,
            "peak_rss_GiB": float("nan"),
            "exit": None,
            "output_tail": f"did not finish in {limit:.0f} s",
        }
    peak = usage.ru_maxrss / 2**20  # KiB on Linux
    return {"wall_s": wall, "peak_rss_GiB": peak, "exit": proc.returncode, "output_tail": tail}


def _entry(name, cli, baseline, truth=None, fit_json=None):
    extra = {}
    if fit_json is not None and fit_json.exists() and cli["exit"] == 0:
        d = json.loads(fit_json.read_text())
        extra["decimation"] = d.get("decimation")
        extra["full_record"] = d.get("full_record")
        if truth:
            extra["errors_in_std"] = {
                k: (d["parameters"][k] - v) / d["std_errors"][k] for k, v in truth.items()
            }
    ok = cli["exit"] == 0 and cli["wall_s"] <= 60 and cli["peak_rss_GiB"] <= 2
    return dict(
        name=name,
        tribojax_s=cli["wall_s"],
        peak_rss_GiB=cli["peak_rss_GiB"],
        baseline=None if baseline is None else "the same command, --decimate off",
        baseline_s=None if baseline is None else baseline["wall_s"],
        ratio=None if baseline is None else baseline["wall_s"] / cli["wall_s"],
        baseline_detail=baseline,
        target="<= 60 s and <= 2 GiB on 2 cores (cold)",
        meets_target=ok,
        exit=cli["exit"],
        **extra,
    )


def run(quick=False, with_baseline=False, only=None, folder=None):
    """Entries for benchmarks/run.py. `quick` skips the (slow) discovery cases."""
    folder = Path(folder or tempfile.mkdtemp(prefix="tribojax-long-"))
    paths = make_records(folder)
    cases = [
        ("fit_slip_1e6", "fit", "slip", ["--alpha", "1"], SLIP_TRUTH),
        ("fit_loop_1e6", "fit", "loop", [], {"mu_N": MU * N_LOAD, "K_d": KD}),
        ("discover_slip_1e6", "discover", "slip", [], None),
        ("discover_loop_1e6", "discover", "loop", [], None),
    ]
    out = []
    for name, cmd, kind, extra, truth in cases:
        if (only and name not in only) or (quick and cmd == "discover"):
            continue
        dest = folder / name
        cli = run_cli([cmd, str(paths[kind]), "--out", str(dest), "--force", *extra])
        base = None
        if with_baseline:
            base = run_cli(
                [
                    cmd,
                    str(paths[kind]),
                    "--out",
                    str(folder / f"{name}-off"),
                    "--force",
                    "--decimate",
                    "off",
                    *extra,
                ]
            )
        fit_json = dest / "fit.json" if cmd == "fit" else None
        out.append(_entry(name, cli, base, truth, fit_json))
        print(
            json.dumps({k: v for k, v in out[-1].items() if k != "baseline_detail"}, default=str),
            flush=True,
        )
    return out


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=None, help="scratch folder for the records and outputs")
    parser.add_argument("--with-baseline", action="store_true")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--only", nargs="*", default=None)
    a = parser.parse_args()
    run(a.quick, a.with_baseline, a.only, a.out)

"""Benchmark: what a command costs a user in a fresh process (issue 31), and the SciPy script.

Each CLI command runs twice in fresh processes: with an empty compilation cache, then with the
cache the first run left (`TRIBOJAX_CACHE_DIR` in the work folder). Each run is split, from JAX's
own compile logging, into start-up (imports and reading the record, up to the first traced
program), tracing, lowering (jaxpr → MLIR),
XLA compilation (or reading a cached program) and the rest (the work, the reading and writing).
The SciPy baseline is the script a user would write for the same fit: `scipy.integrate.solve_ivp`
(LSODA) of the same slip ODE (wang2022 Eq 27 at α = 1) inside `scipy.optimize.least_squares`,
in a fresh process too; the ratio is SciPy end to end / tribojax end to end (> 1: tribojax is
faster).

    python benchmarks/cold_start.py --out DIR [--quick] [--only NAME ...] [--workdir DIR]

`--quick` times `--help`, the import and the fit only; `--only NAME ...` the CLI commands
named. With ../shared present, `discover` on the brfd Imperial Valley history (28,698 samples)
is timed too (`discover_history`, issue 30's 60 s). `run()` returns entries in
benchmarks/run.py's schema.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# the slip run: wang2022's trapezoid over 2.5 s at 0.5 ms, noise 0.3 nm (issue 31's record)
TRUTH = dict(F_s=1.1, K_tau=2.0e7, C_tau=150.0)
SAMPLES, T_END, NOISE = 5001, 2.5, 0.3e-9
FRF_TOML = """
[structure]
M = [[1.0, 0.0], [0.0, 1.0]]
C = [[0.34641016, 0.0], [0.0, 2.0]]
K = [[12.0, 0.0], [0.0, 21.0]]

[[contact]]
type = "elastic2d"
tangential_dof = 0
normal_dof = 1
k_t = 5.0
k_n = 21.0
mu = 0.85

[excitation]
static = [0.0, 100.0]
cosine = [10.0, 1.0]

[harmonics]
H = 8

[range]
omega = [0.01, 6.0]
"""

# Runs one CLI command in this (fresh) process and prints the split of its time as JSON.
_PROBE = r"""
import json, logging, re, sys, time
t0 = time.perf_counter()
split = {"trace_s": 0.0, "lower_s": 0.0, "compile_s": 0.0, "cache_hits": 0, "programs": 0}
class Split(logging.Handler):
    def emit(self, rec):
        m = rec.getMessage()
        t = re.search(r" in ([0-9.eE+-]+) sec", m)
        if m.startswith("Finished tracing") and t:
            split["trace_s"] += float(t.group(1))
        elif m.startswith("Finished jaxpr to MLIR") and t:
            split["lower_s"] += float(t.group(1))
        elif m.startswith("Finished XLA compilation") and t:
            split["compile_s"] += float(t.group(1)); split["programs"] += 1
        elif m.startswith("Persistent compilation cache hit"):
            split["cache_hits"] += 1
h = Split(); h.setLevel(logging.DEBUG)
for name in ("jax._src.dispatch", "jax._src.interpreters.pxla", "jax._src.compiler"):
    lg = logging.getLogger(name); lg.addHandler(h); lg.setLevel(logging.DEBUG); lg.propagate = False
argv = json.loads(sys.argv[1])
from importlib.metadata import entry_points
(script,) = entry_points(group="console_scripts", name="tribojax")
sys.argv = ["tribojax", *argv]
entry = script.load()  # the console script: main(), then an exit without the teardown
main = sys.modules[entry.__module__].main
first = []
class First(logging.Handler):
    def emit(self, rec):
        if not first:
            first.append(time.perf_counter())
f = First(); f.setLevel(logging.DEBUG); logging.getLogger("jax._src.dispatch").addHandler(f)
try:
    code = main(configure=True)  # the console script's process choices (cache, one kernel)
except SystemExit as e:
    code = e.code
# start-up: the imports and the record's reading, up to the end of the first traced program
split["import_s"] = (first[0] if first else time.perf_counter()) - t0
split["total_s"] = time.perf_counter() - t0
split["work_s"] = split["total_s"] - split["import_s"] - split["trace_s"] - split["lower_s"] \
    - split["compile_s"]
split["exit"] = code
print("SPLIT " + json.dumps(split), flush=True)
import os
sys.stderr.flush()
os._exit(code or 0)  # as the console script does
"""

# The fit a user would write with SciPy: read the CSV, LSODA in nm, least_squares on log-params.
_SCIPY = r"""
import csv, json, sys, time
t0 = time.perf_counter()
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares
rows = np.loadtxt(sys.argv[1], delimiter=",", skiprows=1)
t, accel, slip = rows[:, 0], rows[:, 1], rows[:, 2]
mass = json.load(open(sys.argv[2]))["mass_kg"]
def simulate(p):
    F_s, K, C = np.exp(p)
    zmax = F_s / K * 1e9  # nm
    def rhs(tt, y):
        x, v, z = y
        zdot = v * max(1.0 - np.sign(v) * z / zmax, 0.0)
        return [v, np.interp(tt, t, accel) * 1e9 - (K * z + C * zdot) / mass, zdot]
    # max_step: LSODA otherwise steps over the drive's ramps (4 evaluations for the record)
    s = solve_ivp(rhs, (t[0], t[-1]), [0.0, 0.0, 0.0], method="LSODA", t_eval=t, rtol=1e-8,
                  atol=1e-9, max_step=10 * (t[1] - t[0]))
    return s.y[0] * 1e-9 if s.success and s.y.shape[1] == t.size else np.full(t.size, 1e-6)
p0 = np.log([1.0, 1e7, 100.0])
res = least_squares(lambda p: (simulate(p) - slip) / 1e-9, p0, bounds=(p0 - 7, p0 + 7),
                    diff_step=1e-4)
F_s, K, C = np.exp(res.x)
print("SCIPY " + json.dumps({"total_s": time.perf_counter() - t0, "F_s": F_s, "K_tau": K,
      "C_tau": C, "nfev": int(res.nfev), "success": bool(res.success),
      "rms_residual_m": float(np.sqrt(np.mean((res.fun * 1e-9) ** 2)))}))
"""


def _fresh(cmd, env, cwd):
    """(wall seconds, completed process) of `cmd` in a fresh process."""
    t0 = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=cwd)
    return time.perf_counter() - t0, out


def _last(out, tag):
    for line in reversed(out.stdout.splitlines()):
        if line.startswith(tag + " "):
            return json.loads(line[len(tag) + 1 :])
    raise RuntimeError(f"no {tag} line (exit {out.returncode}):\n{out.stderr[-3000:]}")


def _make_record(work: Path) -> Path:
    import tribojax as tj

    el = tj.PreSlipLuGre(**TRUTH)
    run = tj.synthetic_slip_run(el, n=SAMPLES, t_end=T_END, noise=NOISE, seed=1)
    path = work / "run.csv"
    tj.write_slip_run(run, path)
    return path


HISTORY = (
    Path(__file__).resolve().parents[2]
    / "shared"
    / "data"
    / "real"
    / "brfd"
    / "earthquake_ImperialValleyDBE_30lb.json"
)
"""The brfd Imperial Valley history (28,698 samples), timed when ../shared is present."""


def run(quick=False, workdir=None, only=None):
    """The entries (benchmarks/run.py's schema); `only`: the names of the CLI commands to time
    (fit, discover, frf, reproduce, discover_history), default all."""
    work = Path(tempfile.mkdtemp(prefix="tribojax-cold-") if workdir is None else workdir)
    work.mkdir(parents=True, exist_ok=True)
    record = _make_record(work)
    (work / "frf.toml").write_text(FRF_TOML)
    cache = work / "cache"
    shutil.rmtree(cache, ignore_errors=True)
    env = dict(os.environ, TRIBOJAX_CACHE_DIR=str(cache))
    env.pop("JAX_COMPILATION_CACHE_DIR", None)
    exe = shutil.which("tribojax") or "tribojax"
    out = []

    help_s, _ = _fresh([exe, "--help"], env, work)
    import_s, _ = _fresh([sys.executable, "-c", "import tribojax"], env, work)
    first_use_s, _ = _fresh(
        [sys.executable, "-c", "import tribojax; tribojax.PreSlipLuGre"], env, work
    )
    out.append(
        dict(
            name="cli_help",
            tribojax_s=help_s,
            baseline=None,
            baseline_s=None,
            ratio=None,
            target=0.3,
            meets_target=help_s <= 0.3,
        )
    )
    out.append(
        dict(
            name="import_tribojax",
            tribojax_s=import_s,
            first_use_s=first_use_s,
            baseline=None,
            baseline_s=None,
            ratio=None,
            target=1.5,
            meets_target=import_s <= 1.5,
        )
    )

    commands = [
        (
            "fit",
            [
                "fit",
                str(record),
                "--alpha",
                "1",
                "--quiet",
                "--force",
                "--out",
                str(work / "fit-{state}"),
            ],
            3.0,
            10.0,
        )
    ]
    if not quick:
        commands += [
            (
                "discover",
                [
                    "discover",
                    str(record),
                    "--quiet",
                    "--force",
                    "--out",
                    str(work / "discover-{state}"),
                ],
                6.0,
                None,
            ),
            (
                "frf",
                ["frf", str(work / "frf.toml"), "--quiet", "--out", str(work / "frf-{state}")],
                8.0,
                None,
            ),
            (
                "reproduce",
                ["reproduce", "--quiet", "--out", str(work / "reproduce-{state}")],
                20.0,
                None,
            ),
        ]
        if HISTORY.exists():  # issue 30: a 28 s earthquake history discovered in <= 60 s
            commands.append(
                (
                    "discover_history",
                    [
                        "discover",
                        str(HISTORY),
                        "--quiet",
                        "--force",
                        "--out",
                        str(work / "history-{state}"),
                    ],
                    60.0,
                    60.0,
                )
            )
    if only:
        commands = [c for c in commands if c[0] in only]
    for name, argv, warm_target, cold_target in commands:
        runs = {}
        for state in ("empty_cache", "warm_cache"):
            argv_state = [a.replace("{state}", state) for a in argv]
            wall, proc = _fresh([sys.executable, "-c", _PROBE, json.dumps(argv_state)], env, work)
            split = _last(proc, "SPLIT")
            if split["exit"] != 0:
                raise RuntimeError(
                    f"tribojax {' '.join(argv_state)} exited {split['exit']}:\n"
                    f"{proc.stderr[-2000:]}"
                )
            split["end_to_end_s"] = wall
            runs[state] = split
        cold, warm = runs["empty_cache"]["end_to_end_s"], runs["warm_cache"]["end_to_end_s"]
        entry = dict(
            name=f"cli_{name}",
            tribojax_s=warm,
            first_run_s=cold,
            target=warm_target,
            meets_target=warm <= warm_target and (cold_target is None or cold <= cold_target),
            runs=runs,
            baseline=None,
            baseline_s=None,
            ratio=None,
        )
        if name == "fit":  # the SciPy script of the same fit, in a fresh process
            scipy_s, scipy_out = _fresh(
                [sys.executable, "-c", _SCIPY, str(record), str(record.with_suffix(".json"))],
                env,
                work,
            )
            scipy = _last(scipy_out, "SCIPY")
            entry.update(
                baseline="scipy least_squares + solve_ivp LSODA (fresh process)",
                baseline_s=scipy_s,
                ratio=scipy_s / warm,
                ratio_first_run=scipy_s / cold,
                scipy=scipy,
            )
            fit = json.loads((work / "fit-warm_cache" / "fit.json").read_text())
            entry["tribojax_parameters"] = fit.get("parameters")
        out.append(entry)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="folder for cold_start.json")
    parser.add_argument("--quick", action="store_true", help="--help, import and fit only")
    parser.add_argument("--workdir", default=None, help="scratch folder (default: a temp dir)")
    parser.add_argument(
        "--only",
        nargs="*",
        default=None,
        help="time only these commands (fit discover frf reproduce discover_history)",
    )
    args = parser.parse_args(argv)
    results = run(quick=args.quick, workdir=args.workdir, only=args.only)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "cold_start.json").write_text(json.dumps(results, indent=2) + "\n")
    for e in results:
        line = f"{e['name']:<18} {e['tribojax_s']:8.2f} s"
        if "first_run_s" in e:
            line += f"  (first run {e['first_run_s']:.2f} s)"
            for state, r in e["runs"].items():
                line += (
                    f"\n    {state:<12} import {r['import_s']:.2f} trace {r['trace_s']:.2f} "
                    f"lower {r['lower_s']:.2f} compile {r['compile_s']:.2f} "
                    f"work {r['work_s']:.2f} end-to-end {r['end_to_end_s']:.2f} "
                    f"(cache hits {r['cache_hits']})"
                )
        if e.get("baseline_s") is not None:
            line += (
                f"\n    SciPy script {e['baseline_s']:.2f} s: ratio SciPy/tribojax "
                f"{e['ratio']:.2f} warm cache, {e['ratio_first_run']:.2f} first run"
            )
        print(line)
    print(f"wrote {out / 'cold_start.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Experiment (issue 32, stops 63–64): the one-kernel slip solve (opt-in at stop 63, the default
since stop 64; `TRIBOJAX_XLA_HOIST=off` restores XLA's own loops and LAPACK's LU).

    python benchmarks/experiments/one_kernel.py compare     # stored rows: default vs opt-in
    python benchmarks/experiments/one_kernel.py eval        # one fit evaluation, both settings

`compare` reads the rows the opt-in produced (benchmarks/experiments/one_kernel/*_hoisted.jsonl:
the project's study, `benchmarks/discovery_study.py --shard i/2`, and the blind records,
`benchmarks/blind_study.py`, run at commit a141094's arithmetic with the option on) beside the
default's stored rows (benchmarks/discovery_study.json, blind_study_after.jsonl,
blind_pairs_after.jsonl), and the study run in both settings on one machine at stop 64
(`study_default_stop64.jsonl`, `study_hoisted_stop64.jsonl`), and prints both summaries and every
record whose answer changed.
`eval` times one residual-and-Jacobian evaluation of the baseline fit's first start on a
5,001-sample Stribeck record (the LM step's cost), in a fresh process per setting, alternated.
In the stored rows "default" is the LAPACK setting (today's `off`) and "opt-in" the one kernel.
docs/performance.md ("One kernel per solve") has the figures and the reasons.
"""

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent / "one_kernel"

_EVAL = """
import json, os, time, numpy as np
import tribojax.discovery as disc
from tribojax.discovery.synthetic import NOISE_LEVELS, hidden_effect_run
from tribojax._model._residual import _padded, padded_residual
from tribojax._model._fit import SOLVER
from tribojax._fit._engine import value_and_jacobian
b = disc.slip_baseline(hidden_effect_run("stribeck", NOISE_LEVELS["low"], 0.6, seed=0, n=5001,
                                         t_end=2.5))
x0, args = _padded(b, (), list(b.starts())[0], np.asarray(b.data().y), 1e-9)
call = lambda: value_and_jacobian(padded_residual, x0, args, solver=SOLVER)[0].block_until_ready()
call()
times = []
for _ in range(15):
    t = time.perf_counter(); call(); times.append(time.perf_counter() - t)
print(json.dumps(float(np.median(times))))
"""


def _rows(path):
    return [json.loads(x) for x in Path(path).read_text().splitlines() if x.strip()]


def compare():
    sys.path.insert(0, str(ROOT))
    from benchmarks import blind_study, discovery_study

    pairs = [
        (
            "study",
            json.loads((ROOT / "benchmarks/discovery_study.json").read_text())["rows"],
            _rows(HERE / "study_hoisted.jsonl"),
            discovery_study.summarise,
        ),
        (
            "blind",
            _rows(ROOT / "benchmarks/blind_study_after.jsonl"),
            _rows(HERE / "blind_slip_hoisted.jsonl") + _rows(HERE / "blind_loop_hoisted.jsonl"),
            blind_study.summarise,
        ),
        (
            "blind pairs",
            _rows(ROOT / "benchmarks/blind_pairs_after.jsonl"),
            _rows(HERE / "blind_pairs_hoisted.jsonl"),
            blind_study.summarise,
        ),
        (
            "study, both settings on one machine (stop 64)",
            _rows(HERE / "study_default_stop64.jsonl"),
            _rows(HERE / "study_hoisted_stop64.jsonl"),
            discovery_study.summarise,
        ),
    ]
    for name, default, hoisted, summarise in pairs:
        by_label = {r["label"]: r for r in default}
        print(f"## {name}: {len(hoisted)} records")
        for tag, rows in (
            ("default", [by_label[r["label"]] for r in hoisted]),
            ("opt-in", hoisted),
        ):
            table = summarise(rows)[1]
            lines = [x for x in table.splitlines() if x.startswith("- ") and "kPa" not in x]
            seconds = sum(r["seconds"] for r in rows)
            print(f"{tag}: {seconds:.0f} s of discovery")
            if name.startswith("study"):
                for k, v in summarise(rows)[0].items():
                    print(f"  {k}: {v['success']}/{v['n']}")
            else:
                print("\n".join(f"  {x}" for x in lines))
        for r in hoisted:
            d = by_label[r["label"]]
            if (d["ok"], d["effects"], d["verdict"]) != (r["ok"], r["effects"], r["verdict"]):
                print(
                    f"  changed {r['label']}: {d['ok']} {d['effects']} {d['verdict']} -> "
                    f"{r['ok']} {r['effects']} {r['verdict']}"
                )


def evaluate(rounds=3):
    import os

    base = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", "TRIBOJAX_XLA_HOIST")}
    out = {"off": [], "one kernel": []}
    for _ in range(rounds):
        for tag, env in (("off", {"TRIBOJAX_XLA_HOIST": "off"}), ("one kernel", {})):
            res = subprocess.run(
                [sys.executable, "-c", _EVAL],
                env={**base, **env},
                capture_output=True,
                text=True,
                check=True,
            )
            out[tag].append(json.loads(res.stdout.strip().splitlines()[-1]))
    for tag, ts in out.items():
        print(
            f"{tag}: median of 15 evaluations per process: "
            + ", ".join(f"{t * 1e3:.1f} ms" for t in ts)
        )
    return out


if __name__ == "__main__":
    {"compare": compare, "eval": evaluate}[sys.argv[1] if len(sys.argv) > 1 else "compare"]()

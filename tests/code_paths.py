"""How far a reader walks through the code (issue 67): the tribojax functions that `tribojax fit
FILE` and `tribojax discover FILE` run on one record, counted from a trace.

For each command, every call between two tribojax functions is recorded (`sys.setprofile`, the
whole run: command line, record, model, fit, statistics, report). Printed per command:
- stops: distinct tribojax functions entered (named functions and methods; module and class
  bodies, which run at import, and comprehensions and lambdas are not counted);
- files: distinct modules they live in;
- climbs: distinct caller → callee pairs where the callee's package sits in a higher layer
  than the caller's (`tests/test_architecture.py`'s `LAYERS`): the reader climbs back up,
  e.g. an engine calling a model's method it was handed.
It reads the package's internals (layers, the command's in-process entry), as
`test_architecture.py` does, so it lives beside it, not among the benchmarks of the public API.
Run against any checkout (`PYTHONPATH=OTHER/src python tests/code_paths.py`) to compare.

    python tests/code_paths.py [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from inspect import CO_NEWLOCALS
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # beside test_architecture, whose layers it reads
import tribojax as tj  # noqa: E402
from test_architecture import LAYER_OF  # noqa: E402


def _unit(filename: str) -> tuple[str, str] | None:
    """(module, layer unit) of a tribojax source file, None outside tribojax."""
    parts = Path(filename).parts
    if "tribojax" not in parts:
        return None
    rel = parts[len(parts) - 1 - parts[::-1].index("tribojax") :]
    mod = ".".join(rel).removesuffix(".py")
    unit = rel[1].removesuffix(".py") if len(rel) > 2 or rel[1] != "__init__.py" else ""
    return mod, unit


def trace(argv: list[str]) -> dict:
    from tribojax._cli import main

    stops, files, climbs = set(), set(), set()
    stack: list = []

    def profile(frame, event, arg):
        if event == "call":
            here = _unit(frame.f_code.co_filename)
            caller = stack[-1] if stack else None
            stack.append(here)
            code = frame.f_code
            # functions only: module and class bodies run at import, comprehensions and lambdas
            # are parts of the function that holds them
            if here is None or not code.co_flags & CO_NEWLOCALS or code.co_name.startswith("<"):
                return
            name = (here[0], frame.f_code.co_qualname)
            stops.add(name)
            files.add(here[0])
            if caller is not None and caller[1] in LAYER_OF and here[1] in LAYER_OF:
                if LAYER_OF[here[1]][0] > LAYER_OF[caller[1]][0]:
                    climbs.add((caller[0], name))
        elif event == "return" and stack:
            stack.pop()

    sys.setprofile(profile)
    try:
        status = main(argv)
    finally:
        sys.setprofile(None)
    return {
        "status": status,
        "stops": len(stops),
        "files": len(files),
        "climbs": len(climbs),
        "climb_pairs": sorted(f"{a} -> {b[0]}.{b[1]}" for a, b in climbs),
        "file_list": sorted(files),
        "stop_list": sorted(".".join(s) for s in stops),
    }


def records(folder: Path) -> dict:
    loop = tj.synthetic_loop(tj.Jenkins(0.3, 100.0, 2e6), 4.5e-5, 2 * 3.14159 * 50, noise=0.004)
    path = folder / "loop.csv"
    tj.write_loop(loop, path)
    out = {"loop": path}
    curve = ROOT.parent / "shared/data/real/screwdrive/driveNo1/steady_state/0.096kg"
    if curve.exists():
        out["curve"] = curve
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        for label, path in records(Path(tmp)).items():
            for command in ("fit", "discover"):
                out = Path(tmp) / f"{command}-{label}"
                rows[f"{command} {label}"] = row = trace([command, str(path), "--out", str(out)])
                brief = {k: v for k, v in row.items() if not k.endswith(("_pairs", "_list"))}
                print(f"{command:8s} {label:6s} {brief}", flush=True)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()

"""Convert the measured rig data (../shared/data/real or --src) into compact SI copies here.

    python data/real/convert.py --src PATH/TO/real [--out data/real] [--full]

brfd (banded rotary friction damper, CC BY-SA 4.0; the copies carry the same licence): each test
is read by `tribojax.read_brfd` (in → m, kip → N) and written as a loop CSV
`time_s,displacement_m,force_N` with its sidecar. By default only the CI excerpts are written
(the whole 2 Hz / 0.5 in test, the first 4096 samples of the Kocaeli history); `--full` converts
every test. screwdrive (lead-screw drives, MIT): each steady-state folder becomes one friction
curve CSV (`tribojax.read_epos_steady`: rad/s, N m), each start–stop export one transient CSV.
`MANIFEST.json` lists every output with its source file, the original's sha256, the copy's
sha256 and the licence. Existing files are never replaced.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
from pathlib import Path

import tribojax as tj

BRFD = {
    "source": "github.com/ARTS-Laboratory/Dataset-Friction-Damper-with-Backlash, commit "
    "0e09aa9d, data/dataset-3",
    "licence": "CC BY-SA 4.0 (brfd/LICENSE.txt); converted data carry the same licence",
}
SCREW = {
    "source": "github.com/RViMLab/TRO2021-Dynamic-Modelling, commit c3b758b4, experiments/; "
    "A. Mablekos-Alexiou, L. da Cruz, C. Bergeles, IEEE Trans. Robotics 37(4) 1252-1267, 2021",
    "licence": "MIT (screwdrive/LICENSE)",
}
EXCERPTS = {"2Hz30lbtension0.5amplitude": None, "earthquake_KocaeliDBE_30lb": 4096}


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def convert(src: Path, out: Path, full: bool) -> list[dict]:
    entries = []
    for path in sorted((src / "brfd").glob("*.json")):
        if not full and path.stem not in EXCERPTS:
            continue
        loop = tj.read_brfd(path)
        keep = EXCERPTS.get(path.stem) if not full else None
        if keep:
            loop = dataclasses.replace(loop, t=loop.t[:keep], u=loop.u[:keep], f=loop.f[:keep])
        target = out / "brfd" / f"{path.stem}.csv"
        note = (
            f"{path.name} converted to SI (in -> m, kip -> N)"
            + (f", first {keep} samples" if keep else "")
            + f"\n{BRFD['source']}\n"
            + f"Licence: {BRFD['licence']}"
        )
        tj.write_loop(loop, target, note)
        entries.append(
            {
                "file": f"brfd/{target.name}",
                "original": f"brfd/{path.name}",
                "original_sha256": sha256(path),
                **BRFD,
            }
        )
    for drive in sorted((src / "screwdrive").glob("driveNo*")):
        for folder in sorted((drive / "steady_state").iterdir()):
            curve = tj.read_epos_steady(folder)
            target = out / "screwdrive" / f"{drive.name}_steady_{folder.name}.csv"
            originals = sorted(folder.glob("*.csv"))
            prov = {"source": SCREW["source"], "licence": SCREW["licence"]}
            tj.write_friction_curve(
                curve,
                target,
                f"{drive.name}/steady_state/{folder.name}: "
                "one point per EPOS export (mean and scatter)",
                provenance=prov,
            )
            entries.append(
                {
                    "file": f"screwdrive/{target.name}",
                    "original": f"screwdrive/{drive.name}/steady_state/{folder.name}/",
                    "original_sha256": {p.name: sha256(p) for p in originals},
                    **SCREW,
                }
            )
        for path in sorted((drive / "start_stop").glob("*.csv")):
            tr = tj.read_epos_transient(path)
            target = out / "screwdrive" / f"{drive.name}_start_stop_{path.stem}.csv"
            prov = {"source": SCREW["source"], "licence": SCREW["licence"]}
            tj.write_friction_transient(
                tr, target, f"{drive.name}/start_stop/{path.name}", provenance=prov
            )
            entries.append(
                {
                    "file": f"screwdrive/{target.name}",
                    "original": f"screwdrive/{drive.name}/start_stop/{path.name}",
                    "original_sha256": sha256(path),
                    **SCREW,
                }
            )
    for e in entries:
        e["sha256"] = sha256(out / e["file"])
    return entries


def main(argv=None) -> None:
    here = Path(__file__).resolve().parent
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--src", type=Path, default=here.parents[1] / ".." / "shared/data/real")
    parser.add_argument("--out", type=Path, default=here)
    parser.add_argument("--full", action="store_true", help="convert every brfd test")
    args = parser.parse_args(argv)
    entries = convert(args.src, args.out, args.full)
    manifest = {"converted_by": "data/real/convert.py", "files": entries}
    tj.write_json_atomic(args.out / "MANIFEST.json", manifest, exclusive=True)
    print(json.dumps([e["file"] for e in entries], indent=1))


if __name__ == "__main__":
    main()

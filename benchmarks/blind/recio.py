"""Writing records: CSV (17 significant digits), JSON sidecar, manifest."""
import json
import os

import numpy as np


def write_csv(path, header, columns, comment="synthetic record, SI units"):
    """CSV with one '#' comment line, a header line, then rows of %.17g values."""
    data = np.column_stack(columns)
    with open(path, "w", newline="\n") as fh:
        fh.write(f"# {comment}\n{header}\n")
        for row in data:
            fh.write(",".join(f"{x:.17g}" for x in row) + "\n")


def read_csv(path):
    """(header list, 2-D float array) of a record CSV."""
    with open(path) as fh:
        lines = [ln for ln in fh.read().splitlines() if ln and not ln.startswith("#")]
    return lines[0].split(","), np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])


def _clean(obj):
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    return obj


def write_json(path, obj):
    with open(path, "w") as fh:
        json.dump(_clean(obj), fh, indent=1, sort_keys=False)
        fh.write("\n")


def write_record(out_dir, stem, rec):
    """Write <stem>.csv and <stem>.json; return the manifest entry."""
    write_csv(os.path.join(out_dir, stem + ".csv"), rec["header"], rec["columns"])
    write_json(os.path.join(out_dir, stem + ".json"), rec["sidecar"])
    return {"label": rec["label"], "file": stem + ".csv", "kind": rec["kind"],
            "hidden": rec["hidden"], "drive": rec["drive"], "params": rec["params"],
            "seed": rec["seed"], "visibility_sd": rec["visibility_sd"]}

"""Bundled data: checksums as documented, validated loading, malformed files refused."""

import hashlib
import re
from pathlib import Path

import numpy as np
import pytest

import tribojax as tj
from tribojax._tables import data_dir

REPO = Path(__file__).resolve().parents[1]


def test_checksums_match_data_readme():
    readme = (REPO / "data" / "README.md").read_text()
    rows = re.findall(r"\| `([\w.]+\.csv)` \|.*\| `([0-9a-f]{64})` \|", readme)
    assert len(rows) == 9
    for name, digest in rows:
        (path,) = (REPO / "data").glob(f"*/{name}")
        assert hashlib.sha256(path.read_bytes()).hexdigest() == digest, name


def test_tables_load_with_units():
    t1 = tj.wang2022_table(1)
    assert list(t1["surface"]) == ["chuck", "reticle", "equivalent"]
    assert t1["D"][2] == 2.8821 and t1["G_m"][2] == 7.768e-12
    t3 = tj.wang2022_table(3)
    # Eq 26 holds in the published table to the printed digits
    # (row 0 is off by 0.01 nm: 0.4868 / 1.4878e7 = 32.7195 nm, printed 32.7295)
    np.testing.assert_allclose(t3["Fs_N"] / t3["Ktau_N_per_m"] * 1e9, t3["zmax_nm"], rtol=4e-4)
    for n in (4, 5, 6, 7):
        t = tj.wang2022_table(n)
        assert t["vacuum_kPa"].tolist() == [0.6, 2, 4, 7, 10, 20]
    with pytest.raises(ValueError, match="Tables 1-7"):
        tj.wang2022_table(8)
    w1 = tj.wu2015_table(1)
    assert list(w1["material"]) == ["1Cr13"] * 9
    assert sorted(set(w1["radius_mm"])) == [6, 18, 36]
    assert sorted(set(w1["normal_force_N"])) == [1.96, 2.94, 4.90]
    assert w1["frequency_Hz"].tolist() == [22] * 6 + [82] * 3
    with pytest.raises(ValueError, match="one table"):
        tj.wu2015_table(2)


def test_data_dir_is_found_from_any_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert (data_dir() / "wang2022" / "table3_contact.csv").is_file()


@pytest.mark.parametrize(
    "text, pattern",
    [
        ("a,b\n1,2\n3\n", r"line 3: 1 fields, the header has 2"),
        ("# c\na,b\n1,x\n", r"line 3: column 'b' holds 'x', not a number"),
        ("a,b\n1,nan\n", r"line 2: column 'b' is nan"),
        ("a,a\n1,2\n", r"line 1: header has empty or repeated names"),
        ("# only comments\n", r"no header line"),
        ("a,b\n", r"no data rows"),
        ("x,y\n1,2\n", r"line 1: missing column\(s\) \['a'\]"),
    ],
)
def test_malformed_files_are_refused_with_file_and_line(tmp_path, text, pattern):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    before = path.read_bytes()
    with pytest.raises(tj.DataFileError, match=re.escape(str(path)) + ".*" + pattern):
        tj.read_table(path, columns=("a",))
    assert path.read_bytes() == before  # nothing the user gave is touched


def test_unreadable_file(tmp_path):
    with pytest.raises(tj.DataFileError, match="cannot be read"):
        tj.read_table(tmp_path / "missing.csv")

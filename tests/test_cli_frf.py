"""`tribojax frf CONFIG.toml`: outputs, and clear errors for bad configurations."""

import json

import pytest

from tribojax._cli import main

CONFIG = """
[structure]
M = [[1.0]]
C = [[1.0]]
K = [[100.0]]

[[contact]]
type = "jenkins"
dof = 0
mu = 1.0
N = 1.0
K_d = 100.0

[excitation]
cosine = [1.0]

[harmonics]
set = [1, 3]

[range]
omega = [6.0, 18.0]
"""


def test_frf_cli_writes_curve(tmp_path, capsys):
    cfg = tmp_path / "sdof.toml"
    cfg.write_text(CONFIG)
    out = tmp_path / "out"
    assert main(["frf", str(cfg), "--out", str(out)]) == 0
    res = json.loads((out / "frf.json").read_text())
    assert res["result"] == "successful" and res["harmonics"] == [1, 3]
    # the slipping resonance lies between the slip (10 rad/s) and stick (14.1 rad/s) frequencies
    assert 10.0 < res["peaks"][0]["omega"] < 14.1
    assert len(res["omega"]) == len(res["amplitude"]) == len(res["stable"]) > 10
    lines = (out / "frf.csv").read_text().splitlines()
    assert lines[0] == "omega_rad_per_s,amplitude_dof0_m,stable"
    assert len(lines) == len(res["omega"]) + 1


@pytest.mark.parametrize(
    "change, message",
    [
        (("dof = 0", "dof = 2"), "DOF 2"),
        (("omega = [6.0, 18.0]", "omega = [0.0, 18.0]"), "frequency range"),
        (("set = [1, 3]", "H = 0"), "H = 0"),
        (("M = [[1.0]]", "M = [[-1.0]]"), "positive definite"),
        (('type = "jenkins"', 'type = "spring"'), "not one of"),
        (("K_d = 100.0", 'K_d = "stiff"'), "K_d"),
        (("[range]", "[ranges]"), "unknown table"),
    ],
)
def test_frf_cli_bad_config(tmp_path, capsys, change, message):
    cfg = tmp_path / "bad.toml"
    cfg.write_text(CONFIG.replace(*change))
    assert main(["frf", str(cfg), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert message in err and "bad.toml" in err
    assert not (tmp_path / "out").exists()

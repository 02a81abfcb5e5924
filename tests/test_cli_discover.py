"""`tribojax discover FILE.csv`: output contract, refusals and exit codes (in-process)."""

import json

import pytest

import tribojax.discovery as disc
from tribojax._cli._main import main
from tribojax._io._slip_run import write_slip_run
from tribojax.discovery.synthetic import NOISE_LEVELS, hidden_effect_run


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    d = tmp_path_factory.mktemp("rec")
    # 461 samples: the shape of the verdict tests' records (one compile in their shared unit)
    run = hidden_effect_run("position_error", NOISE_LEVELS["low"], 0.6, n=461)
    path = d / "run.csv"
    write_slip_run(run, path)
    return path


def test_discover_writes_contract_and_figure(record, tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["discover", str(record), "--out", str(out)])
    assert code == 0
    data = json.loads((out / "discovery.json").read_text())
    assert data["effect"] == "position_error" and data["effects"][0] == "position_error"
    assert data["final_rmse"] < data["baseline_rmse"] / 2
    for c in data["candidates"]:
        assert {"name", "score", "delta_bic"} <= set(c)
    assert isinstance(data["regions"], list) and data["regions"]
    assert (out / "discovery.png").stat().st_size > 1000
    assert "position_error" in capsys.readouterr().out
    # refuses to overwrite an earlier result without --force
    before = (out / "discovery.json").read_text()
    assert main(["discover", str(record), "--out", str(out)]) == 2
    assert (out / "discovery.json").read_text() == before
    assert "exists" in capsys.readouterr().err


def test_never_writes_over_the_input(tmp_path, capsys):
    csv = tmp_path / "discovery.csv"
    csv.write_text("time_s,stage_accel_m_s2,slip_m\n0,0,0\n")
    (tmp_path / "discovery.json").write_text('{"mass_kg": 0.321}')
    before = (tmp_path / "discovery.json").read_text()
    assert main(["discover", str(csv), "--out", str(tmp_path), "--force"]) == 2
    assert (tmp_path / "discovery.json").read_text() == before
    assert "overwrite the input" in capsys.readouterr().err


def test_malformed_file_exits_nonzero(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,stage_accel_m_s2,slip_m\n0,0,0\n0.1,abc,0\n")
    (tmp_path / "bad.json").write_text('{"mass_kg": 0.321}')
    assert main(["discover", str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "bad.csv" in err
    assert not (tmp_path / "o" / "discovery.json").exists()


def test_loop_records_dispatch(tmp_path, capsys):
    import numpy as np

    from tribojax._io._loop import HysteresisLoop, write_loop

    t = np.linspace(0, 3 / 22, 600, endpoint=False)
    u = 1e-6 * np.cos(2 * np.pi * 22 * t)
    loop = HysteresisLoop(t=t, u=u, f=1e6 * u, normal_load=2.94, frequency=22.0)
    path = tmp_path / "loop.csv"
    write_loop(loop, path)
    code = main(["discover", str(path), "--out", str(tmp_path / "o")])
    if hasattr(disc, "loop_baseline"):
        assert code in (0, 3)
        assert (tmp_path / "o" / "discovery.json").exists()
    else:
        assert code == 2
        assert "not available" in capsys.readouterr().err

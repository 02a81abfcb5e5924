"""What the commands write: never an existing result or their own input without --force, never
two runs' files mixed, no folder left stuck after a kill (issue 33, items 4 and 5)."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from tribojax._cli._main import main

CONTACT = ["contact", "--D", "2.5", "--G", "1e-9", "--load", "5"]


def _err_line(capsys, cmd):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"tribojax {cmd}: error:"), err
    return err[0]


def test_contact_json_never_replaces_a_file_or_its_input_without_force(tmp_path, capsys):
    target = tmp_path / "r.json"
    target.write_text("earlier")
    assert main([*CONTACT, "--json", str(target)]) == 2
    assert "exists" in _err_line(capsys, "contact") and target.read_text() == "earlier"
    assert main([*CONTACT, "--json", str(target), "--force"]) == 0
    assert json.loads(target.read_text())["contact"][0]["load_N"] == 5.0
    # its own input: refused even with --force (the surface would become JSON)
    topo = tmp_path / "t.npy"
    x = np.linspace(0, 1, 64)
    np.save(topo, np.outer(np.sin(7 * x), np.cos(5 * x)) * 1e-6)
    before = topo.read_bytes()
    args = ["contact", "--topography", str(topo), "--dx", "1e-6", "--load", "5"]
    assert main([*args, "--json", str(topo), "--force"]) == 2
    assert "is an input file" in _err_line(capsys, "contact") and topo.read_bytes() == before


def test_hysteresis_out_keeps_an_earlier_result_and_never_mixes_runs(tmp_path, capsys):
    out = tmp_path / "h"
    out.mkdir()
    (out / "loop_fit.json").write_text("{}")  # an earlier run with --loop
    cmd = ["hysteresis", "--n", "4", "--out", str(out)]
    assert main(cmd) == 2
    assert "earlier result" in _err_line(capsys, "hysteresis")
    assert sorted(p.name for p in out.iterdir()) == ["loop_fit.json"]
    # --force: a loop_fit.json the command did not write (a user's) is left as it is ...
    assert main([*cmd, "--force"]) == 0
    assert "not written by tribojax hysteresis" in capsys.readouterr().err
    assert (out / "loop_fit.json").read_text() == "{}"
    # ... and an earlier run's loop fit does not stay beside this run's files
    (out / "loop_fit.json").write_text('{"written_by": "tribojax hysteresis"}')
    assert main([*cmd, "--force"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["hysteresis.csv", "hysteresis.png"]


def test_a_lock_left_by_a_dead_run_is_taken_over(tmp_path, capsys):
    out = tmp_path / "c"
    out.mkdir()
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    (out / ".r.json.lock").write_text(dead.stdout)
    assert main([*CONTACT, "--json", str(out / "r.json")]) == 0
    err = capsys.readouterr().err
    assert "taking over the lock" in err and f"process {dead.stdout.strip()}" in err
    assert sorted(p.name for p in out.iterdir()) == ["r.json"]
    # a live owner (this process, stamped as a run stamps it) still keeps a second run out
    from tribojax._cli._lock import lock_stamp

    (out / ".s.json.lock").write_text(lock_stamp())
    assert main([*CONTACT, "--json", str(out / "s.json")]) == 2
    assert "another tribojax run is writing" in _err_line(capsys, "contact")


def test_a_bare_or_empty_lock_of_no_run_is_taken_over(tmp_path, capsys):
    # issue 72 probe: a lock holding only the id of a live process that is not a tribojax run
    # (an older stamp, or written by hand), or an empty one left by a writer killed before it
    # wrote its stamp, blocked the folder forever
    out = tmp_path / "c"
    out.mkdir()
    sleeper = subprocess.Popen(["sleep", "60"])
    try:
        (out / ".r.json.lock").write_text(f"{sleeper.pid}\n")
        assert main([*CONTACT, "--json", str(out / "r.json")]) == 0
        assert f"process {sleeper.pid}" in capsys.readouterr().err
    finally:
        sleeper.kill()
        sleeper.wait()
    empty = out / ".s.json.lock"
    empty.write_text("")
    assert main([*CONTACT, "--json", str(out / "s.json")]) == 2  # a writer may be stamping it
    os.utime(empty, (time.time() - 60, time.time() - 60))
    assert main([*CONTACT, "--json", str(out / "s.json")]) == 0
    assert "no process recorded" in capsys.readouterr().err


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGINT"])
def test_a_killed_run_exits_130_and_leaves_no_lock_or_output(tmp_path, sig):
    out = tmp_path / "o"
    code = textwrap.dedent(f"""
        import os, signal, sys, time
        from tribojax._cli._common import claim_outputs, run_command
        # as from a terminal: a suite started in the background by a shell without job control
        # passes SIGINT on ignored, and Python then installs no KeyboardInterrupt handler
        signal.signal(signal.SIGINT, signal.default_int_handler)
        def work(args):
            with claim_outputs(None, [{str(out / "r.json")!r}], force=False):
                open({str(out / "r.json")!r}, "w").write("partial")
                os.kill(os.getpid(), signal.{sig})
                time.sleep(30)
            return 0
        sys.exit(run_command("fit", work, None))
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    how = "SIGTERM" if sig == "SIGTERM" else "Ctrl-C"
    assert proc.returncode == 130, proc.stderr
    assert proc.stderr.strip() == f"tribojax fit: interrupted ({how})"
    assert not out.exists()  # output, lock and the folder made for them removed


def test_the_console_script_exits_with_the_status_and_its_output_written(tmp_path):
    # `entry` ends the process without the interpreter's teardown: what it printed and wrote
    # must be complete, and the status the command's
    code = "import sys; from tribojax._cli import entry; sys.argv[0] = 'tribojax'; entry()"

    def run(*args):
        return subprocess.run(
            [sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300
        )

    ok = run(*CONTACT, "--json", str(tmp_path / "r.json"))
    assert ok.returncode == 0, ok.stderr[-2000:]
    rows = json.loads((tmp_path / "r.json").read_text())["contact"]
    assert rows and ok.stdout.rstrip().endswith(str(tmp_path / "r.json")), ok.stdout[-500:]
    bad = run(*CONTACT, "--mass", "0")
    assert bad.returncode == 2 and bad.stderr.startswith("tribojax contact: error: --mass = ")


def test_contact_numbers_outside_their_physical_range_are_not_a_result(tmp_path, capsys):
    # issue 33 probe: C_tau = 7.82, 0.139, -0.287, -852, 3.3e5 N s/m at these loads, exit 0
    out = tmp_path / "c.json"
    loads = ["1e2", "1e4", "1e6", "1e8", "1e12"]
    assert main(["contact", "--D", "2.5", "--G", "1e-9", "--load", *loads, "--json", str(out)]) == 1
    rows = json.loads(out.read_text())["contact"]
    err = capsys.readouterr().err
    for row in rows:
        values = [row[k] for k in ("Fs_N", "Ktau_N_per_m", "Ctau_Ns_per_m", "zmax_m")]
        ok = all(v is not None and np.isfinite(v) and v >= 0 for v in values)
        assert row["in_range"] == ok
        assert (f"load {row['load_N']:g} N:" in err) == (not ok)
    assert rows[0]["in_range"] and not all(r["in_range"] for r in rows)


@pytest.mark.parametrize("flag, value", [("--mu-t", "inf"), ("--mass", "0"), ("--gamma", "1")])
def test_contact_constants_outside_their_range_are_bad_input(capsys, flag, value):
    assert main([*CONTACT, flag, value]) == 2
    assert f"{flag} = " in _err_line(capsys, "contact")


@pytest.mark.parametrize(
    "flag, value", [("--omega", "0"), ("--omega", "nan"), ("--N", "-1"), ("--C-tau", "-1")]
)
def test_hysteresis_bad_numbers_are_one_line_and_exit_2(tmp_path, capsys, flag, value):
    # issue 33 probe: --omega 0 printed two JAX/equinox tracebacks and exited 1
    out = tmp_path / "h"
    assert main(["hysteresis", "--n", "4", "--out", str(out), flag, value]) == 2
    assert f"{flag} = " in _err_line(capsys, "hysteresis")
    assert not out.exists()


@pytest.mark.parametrize(
    "name, data, expect",
    [
        ("u16.csv", "t_s,u_m,f_N\n0,0,0\n".encode("utf-16"), "UTF-16 text"),
        ("nul.csv", b"\x00" * 4096, "line 1: a NUL byte"),
        ("semi.csv", b"t_s;u_m;f_N\n0;0,1;0\n", "separated by semicolons"),
        ("tab.csv", b"t_s\tu_m\tf_N\n0\t0\t0\n", "separated by tabs"),
        (
            "long.csv",
            b"t_s,u_m,f_N\n" + b"1" * 200_000 + b",0,0\n",
            "long.csv, line 2: field larger",
        ),
    ],
)
def test_unreadable_files_are_named_with_the_reason(tmp_path, capsys, name, data, expect):
    # issue 33 probes: UTF-16 was called "Windows-1252 or Latin-1 text?", a zero-byte file and a
    # line over 131,072 characters gave csv's message without file or line, other separators no
    # hint
    src = tmp_path / name
    src.write_bytes(data)
    assert main(["fit", str(src), "--out", str(tmp_path / "o")]) == 2
    line = _err_line(capsys, "fit")
    assert expect in line and name in line, line
    assert not (tmp_path / "o").exists()


def test_ctrl_c_during_start_up_is_one_line_and_130(capsys, monkeypatch):
    # issue 72 row 10: an interrupt before the subcommand runs (JAX's import) was a 10-14-line
    # KeyboardInterrupt traceback and exit -2
    from tribojax._cli import _main

    def interrupted():
        raise KeyboardInterrupt

    monkeypatch.setattr(_main, "configure_process", interrupted)
    assert _main.console(CONTACT) == 130
    assert capsys.readouterr().err == "tribojax contact: interrupted (Ctrl-C)\n"


def test_an_interrupt_swallowed_by_a_callback_still_ends_the_run_130(capsys, monkeypatch):
    # ... and one landing in a garbage-collection callback ("Exception ignored in
    # _xla_gc_callback") was lost: the run went on and exited 0
    import gc

    from tribojax._cli import _main

    class Collected:
        def __del__(self):
            signal.raise_signal(signal.SIGINT)  # Python cannot raise it here: "ignored"

    def configure():
        Collected()
        gc.collect()

    monkeypatch.setattr(_main, "configure_process", configure)
    assert _main.console(CONTACT) == 130
    err = capsys.readouterr().err
    assert err == "tribojax contact: interrupted (Ctrl-C)\n", err
    assert signal.getsignal(signal.SIGINT) is not _main._on_signal  # the handler put back


def test_a_real_ctrl_c_at_start_up(tmp_path):
    # "ready" once the console script's module is imported (its handler is installed next);
    # the interrupt then lands while the command imports JAX (~1-2 s)
    code = (
        "import sys; from tribojax._cli import entry; print('ready', flush=True); "
        "sys.argv[0] = 'tribojax'; entry()"
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", code, *CONTACT],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout.readline() == "ready\n"
    time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and err == "tribojax contact: interrupted (Ctrl-C)\n", err

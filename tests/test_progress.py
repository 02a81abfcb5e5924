"""The progress display of the long subcommands: shown on a terminal, silent in a pipe and with
`--quiet`, and never mixed into the command's own output."""

import io
import sys

import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj
from tribojax._cli._common import Progress
from tribojax._cli._main import LONG_RUNNING, build_parser, main


class FakeTerminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_on_a_terminal_draws_bar_and_notes():
    err, stdout = FakeTerminal(), sys.stdout
    with Progress("reproduce", total=4, stream=err) as bar:
        bar.step("Tables 4-7")
        bar.note("LM: 3 steps,\n cost 0.5")
        print("a table line")  # the command's own output goes above the display
    text = err.getvalue()
    assert "\r\x1b[Kreproduce [#####---------------] 1/4" in text
    assert "LM: 3 steps, cost 0.5" in text  # one line, whitespace collapsed
    assert text.endswith("\r\x1b[K")  # the display is cleared at the end
    assert sys.stdout is stdout  # restored


def test_output_lines_stay_whole_on_a_shared_terminal(monkeypatch):
    # stdout and stderr on one terminal: a printed line is never erased or split by the display
    term = FakeTerminal()
    monkeypatch.setattr(sys, "stdout", term)
    with Progress("fit", stream=term) as bar:
        print("first result line")
        bar.note("LM: 2 steps")
        print("second", "line")
    text = term.getvalue()
    assert "\r\x1b[Kfirst result line\n\r\x1b[Kfit" in text
    assert "\r\x1b[Ksecond line\n" in text
    assert text.endswith("\r\x1b[K")


@pytest.mark.parametrize(
    "stream, quiet", [(io.StringIO(), False), (FakeTerminal(), True)], ids=["pipe", "quiet"]
)
def test_progress_silent_in_a_pipe_and_when_quiet(stream, quiet):
    stdout = sys.stdout
    with Progress("fit", stream=stream, quiet=quiet) as bar:
        assert sys.stdout is stdout  # stdout untouched when nothing is shown
        bar.step("x")
        bar.note("LM: 1 step")
    assert stream.getvalue() == ""


def test_long_subcommands_take_quiet():
    parser = build_parser()
    assert set(LONG_RUNNING) == {"reproduce", "fit", "discover", "frf"}
    args = parser.parse_args(["fit", "x.csv", "--quiet"])
    assert args.quiet
    with pytest.raises(SystemExit):
        parser.parse_args(["contact", "--D", "2.5", "--G", "1e-9", "--load", "1", "--quiet"])


@pytest.fixture
def loop_file(tmp_path):
    mu, N, K_d = 0.3, 2.94, 1.2e6
    loop = tj.synthetic_loop(
        tj.Mindlin(mu, N, K_d), 3 * mu * N / K_d, 2 * np.pi * 22, noise=0.004, seed=4, normal_load=N
    )
    path = tmp_path / "loop.csv"
    tj.write_loop(loop, path)
    return path


@pytest.mark.parametrize(
    "terminal, quiet, shown",
    [(True, False, True), (False, False, False), (True, True, False)],
    ids=["terminal", "pipe", "quiet"],
)
def test_fit_command_progress(loop_file, monkeypatch, capsys, terminal, quiet, shown):
    err = FakeTerminal() if terminal else io.StringIO()
    monkeypatch.setattr(sys, "stderr", err)
    argv = ["fit", str(loop_file), "--out", str(loop_file.parent / "out")]
    assert main(argv + (["--quiet"] if quiet else [])) == 0
    out = capsys.readouterr().out
    assert ("\r\x1b[Kfit" in err.getvalue()) == shown
    assert "\r" not in out and "mu_N" in out  # the result lines are clean


def _exp_residuals(theta, args):
    t, y, scale = args
    return scale * (theta[0] * jnp.exp(-theta[1] * t) - y)


def test_fits_side_by_side_report_to_their_own_progress():
    """The progress callable is passed to the solve as an argument (a channel number), not
    pushed on a shared stack: two fits in threads each hear only their own steps (issue 67)."""
    from concurrent.futures import ThreadPoolExecutor

    from tribojax._fit._solver import LevenbergMarquardt

    t = jnp.linspace(0.0, 4.0, 40)
    y = 2.0 * jnp.exp(-0.7 * t)
    solver = LevenbergMarquardt.noise_floor(1e-12, 1e-14, report=True)
    heard = {1.0: [], 1e6: []}

    def run(scale):
        return tj.least_squares_fit(
            _exp_residuals,
            jnp.array([1.0, 0.2]),
            (t, y, jnp.asarray(scale)),
            names=("a", "k"),
            jac="fwd",
            solver=solver,
            progress=heard[scale].append,
        )

    with ThreadPoolExecutor(2) as pool:
        fits = list(pool.map(run, (1.0, 1e6)))
    assert all(f.values == pytest.approx([2.0, 0.7], rel=1e-8) for f in fits)
    for scale, lines in heard.items():
        assert lines and all(line.startswith("LM: ") for line in lines)
        first = float(lines[0].split("cost ")[1].split(",")[0])
        assert (first > 1e6) == (scale == 1e6), lines[0]  # its own fit's cost, not the other's

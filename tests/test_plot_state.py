"""The package's figures leave matplotlib's global state alone: the user's backend and pyplot's
list of open figures are the same after a plot as before (a notebook keeps its inline figures)."""

import os
import subprocess
import sys

import pytest

CODE = """
import sys
import matplotlib
matplotlib.use("svg")  # a backend that is not Agg: a library switching to Agg would show
import matplotlib.pyplot as plt
from matplotlib.figure import Figure
import numpy as np
import tribojax as tj

png, bar = sys.argv[1], sys.argv[2]
a = np.linspace(0.05, 4.5, 40)
curves = {"A_bar": a.tolist()}
for q in "KC":
    for name in ("jenkins", "mindlin", "eq7"):
        curves[f"{name}_{q}"] = (np.exp(-a) if q == "K" else a * np.exp(-a)).tolist()
rms = {name: {"K": 0.01, "C": 0.02} for name in ("jenkins", "mindlin")}
assert tj.plot_wu2015({"curves": curves, "eq7_rms": rms}, png) is True
e = tj.elasticities(lambda p: {"a": p["x"] ** 2 * p["y"]}, {"x": 2.0, "y": 3.0})
shown = e.plot()  # no file: the figure is returned for display
written = e.plot(bar)
assert isinstance(shown, Figure) and isinstance(written, Figure)
print(matplotlib.get_backend(), plt.get_fignums(), "matplotlib.pyplot" in sys.modules)
"""


def test_plots_keep_the_users_backend_and_pyplot_state(tmp_path):
    pytest.importorskip("matplotlib")
    png, bar = tmp_path / "wu2015.png", tmp_path / "bar.png"
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    run = subprocess.run(
        [sys.executable, "-c", CODE, str(png), str(bar)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    backend, fignums = run.stdout.strip().splitlines()[-1].split(" ", 1)
    assert backend == "svg"
    assert fignums.startswith("[] ")  # pyplot holds no figure of the package
    for path in (png, bar):
        assert path.stat().st_size > 1000, path
    assert not list(tmp_path.glob("*.tmp*"))  # the temporary files are gone

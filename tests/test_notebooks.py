"""Execute every notebook in `notebooks/` and fail on any cell error.

The notebooks are stored without outputs; here each one is run top to bottom with nbclient in a
fresh "python3" kernel, from the notebooks folder (so relative paths behave as in Jupyter), with
the non-interactive matplotlib backend. The executed copy is never written back. Skipped when the
notebook tooling (nbclient, nbformat, ipykernel) is not installed.
"""

import os
import re
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

NOTEBOOK_DIR = Path(__file__).resolve().parents[1] / "notebooks"
NOTEBOOKS = sorted(NOTEBOOK_DIR.glob("*.ipynb"))
CELL_TIMEOUT_S = 600
ANSI_ESCAPE = re.compile(r"\x1b\[[0-9;]*m")  # IPython colours its tracebacks


def test_notebooks_exist():
    assert NOTEBOOKS, f"no notebooks found in {NOTEBOOK_DIR}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_runs(path, monkeypatch):
    # The kernel is a subprocess and inherits this environment.
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        nb,
        kernel_name="python3",
        timeout=CELL_TIMEOUT_S,
        resources={"metadata": {"path": str(NOTEBOOK_DIR)}},  # the kernel's working directory
    )
    try:
        client.execute(cwd=str(NOTEBOOK_DIR), env=dict(os.environ))
    except nbclient.exceptions.CellExecutionError as err:
        message = ANSI_ESCAPE.sub("", str(err))
        pytest.fail(f"{path.name}: a cell raised\n{message}", pytrace=False)

"""The documentation site: notebooks executed once, `mkdocs build --strict`, pages in Chromium.

The tests run in definition order on one worker (one unit of work, tests/conftest.py):

1. each notebook in `notebooks/` runs top to bottom in a fresh kernel (nbclient); a cell error
   fails with the notebook's name and the cell's traceback. The executed copy is staged in
   `build/docs-staged/` (`docs/hooks.py`), so the build below executes nothing again;
2. `mkdocs build --strict` builds the site from the staged copies: a broken link, a public name
   without a docstring or a notebook cell error fails it;
3. headless Chromium (the Debian `chromium` package; skipped when absent) opens the built pages:
   every notebook page must show its figures (non-blank plot regions in a screenshot), and the
   search index must list the pages.
"""

import base64
import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("nbformat")
pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")
pytest.importorskip("mkdocs", reason="the docs extra is not installed (pip install -e '.[docs]')")
yaml = pytest.importorskip("yaml")
Image = pytest.importorskip("PIL.Image")

REPO = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("tribojax_docs_hooks", REPO / "docs" / "hooks.py")
hooks = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(hooks)

NOTEBOOKS = hooks.notebooks()
CHROMIUM = next(
    (p for p in map(shutil.which, ("chromium", "chromium-browser", "google-chrome")) if p), None
)
WIDTH = 1280


def test_notebooks_exist():
    assert NOTEBOOKS, f"no notebooks found in {hooks.NOTEBOOK_DIR}"


EXECUTED: set = set()  # notebooks executed by this process


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_runs(path):
    try:
        staged = hooks.execute_notebook(path)
    except hooks.NotebookError as err:
        pytest.fail(str(err), pytrace=False)
    assert hooks.staged_fresh(path) and staged.exists()
    EXECUTED.add(path)


def test_cell_error_names_notebook_and_cell(tmp_path, monkeypatch):
    import nbformat

    bad = tmp_path / "zz_broken.ipynb"
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell("x = 1"), nbformat.v4.new_code_cell("1 / (x - 1)")]
    nbformat.write(nb, bad)
    monkeypatch.setattr(hooks, "STAGE", tmp_path / "stage")
    with pytest.raises(hooks.NotebookError, match=r"zz_broken\.ipynb(.|\n)*ZeroDivisionError"):
        hooks.execute_notebook(bad)
    assert not hooks.staged_path(bad).exists()


def test_every_public_name_has_a_docstring():
    names = [n for group in hooks.public_names().values() for n in group]
    assert len(names) > 150 and "tribojax.FractalContact" in names
    assert "tribojax.discovery.discover" in names
    assert hooks.missing_docstrings(names) == []


def _mkdocs(config: Path, site: Path):
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    return subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config), "-d", str(site)],
        cwd=config.parent,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )


def test_strict_build_fails_on_a_broken_link(tmp_path):
    # the site's own link validation, on a two-page site without the notebooks and API
    validation = yaml.safe_load((REPO / "mkdocs.yml").read_text())["validation"]
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "index.md").write_text("# A\n\n[to B](b.md) and [gone](missing.md)\n")
    (tmp_path / "docs" / "b.md").write_text("# B\n\n[back](index.md#no-such-heading)\n")
    config = tmp_path / "mkdocs.yml"
    config.write_text(yaml.safe_dump({"site_name": "t", "validation": validation}))
    run = _mkdocs(config, tmp_path / "site")
    assert run.returncode != 0
    assert "missing.md" in run.stderr and "no-such-heading" in run.stderr


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site")
    t0 = time.perf_counter()
    run = _mkdocs(REPO / "mkdocs.yml", out)
    return out, run, time.perf_counter() - t0


@pytest.mark.slow
def test_site_builds_strict(site, request):
    out, run, _ = site
    assert run.returncode == 0, f"mkdocs build --strict failed:\n{run.stderr[-6000:]}"
    selected = {
        i.callspec.params["path"]
        for i in request.session.items
        if i.originalname == "test_notebook_runs"
    }
    if selected == set(NOTEBOOKS):
        # this file is one unit of work (tests/conftest.py): the notebooks ran in this process,
        # before the build, which reuses their staged copies
        assert EXECUTED == set(NOTEBOOKS), "notebook tests ran in another worker process"
        assert "no fresh staged copy" not in run.stderr, run.stderr[-3000:]
    for page in ("index.html", "api/contact/index.html", "reproduction/index.html"):
        assert (out / page).exists(), page
    api = (out / "api" / "contact" / "index.html").read_text()
    assert "FractalContact" in api and "Eq 4" in api  # rendered docstrings
    for nb in NOTEBOOKS:
        html = (out / "examples" / nb.stem / "index.html").read_text()
        figures = len(re.findall(r'<img[^>]+src="data:image/png', html))
        assert figures >= 1, f"{nb.name}: the page has no figure"
        assert "Traceback" not in html, nb.name


@pytest.mark.slow
def test_search_index_lists_the_pages(site):
    out, run, _ = site
    assert run.returncode == 0
    index = json.loads((out / "search" / "search_index.json").read_text())
    locations = {d["location"].split("#")[0] for d in index["docs"]}
    assert {"", "contact/", "api/fit/", "examples/02_reticle_slip/"} <= locations
    text = " ".join(d["text"] for d in index["docs"])
    assert "Levenberg" in text and "least_squares_fit" in text


# Shows only the notebook's output images, stacked on white, each in a magenta frame: the
# screenshot's frames locate the rendered figures.
FIGURES_ONLY = """<style>
.md-header, .md-tabs, .md-sidebar, .md-footer, .jp-InputArea, .jp-MarkdownCell,
.jp-InputPrompt, .jp-OutputPrompt, .md-content__button,
.jp-OutputArea-output:not(:has(img)) { display: none !important; }
body * { visibility: hidden !important; background: #fff !important; }
.jp-OutputArea-output img { visibility: visible !important; outline: 4px solid #f0f !important;
  outline-offset: 2px; margin: 12px !important; max-width: 1100px !important;
  height: auto !important; }
</style></head>"""
FRAME = 4  # px


def _frames(shot: np.ndarray) -> list[tuple[int, int, int, int]]:
    """(top, bottom, left, right) of the inside of each magenta frame, top to bottom."""
    magenta = (shot[..., 0] > 230) & (shot[..., 1] < 30) & (shot[..., 2] > 230)
    edges = _blocks(magenta.sum(axis=1) > 100, gap=1)  # the frames' top and bottom edges
    frames = []
    for (_, top), (bottom, _) in zip(edges[::2], edges[1::2]):
        cols = np.flatnonzero(magenta[(top + bottom) // 2])
        left = cols[cols < cols.mean()].max() if cols.size else 0
        right = cols[cols > cols.mean()].min() if cols.size else 0
        frames.append((top + 1 + FRAME, bottom - FRAME, left + 1 + FRAME, right - FRAME))
    return frames


def _png_heights(html: str) -> list[int]:
    """Natural heights (px) of the page's inline PNG figures (from each PNG's IHDR chunk)."""
    heights = []
    for data in re.findall(r'<img[^>]+src="data:image/png;base64,([A-Za-z0-9+/=]{40})', html):
        heights.append(int.from_bytes(base64.b64decode(data)[20:24], "big"))
    return heights


def _screenshot(html: Path, png: Path, height: int) -> np.ndarray:
    subprocess.run(
        [
            CHROMIUM,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--force-device-scale-factor=1",
            f"--window-size={WIDTH},{height}",
            f"--screenshot={png}",
            html.as_uri(),
        ],
        check=True,
        capture_output=True,
        timeout=120,
    )
    return np.asarray(Image.open(png).convert("RGB"), dtype=float)


def _blocks(ink_rows: np.ndarray, gap: int = 8) -> list[tuple[int, int]]:
    """Runs of rows with ink, merged across gaps shorter than `gap`."""
    rows = np.flatnonzero(ink_rows)
    if rows.size == 0:
        return []
    cuts = np.flatnonzero(np.diff(rows) > gap)
    starts = np.r_[rows[0], rows[cuts + 1]]
    ends = np.r_[rows[cuts], rows[-1]]
    return list(zip(starts.tolist(), ends.tolist()))


@pytest.mark.slow
@pytest.mark.skipif(
    CHROMIUM is None, reason="headless Chromium not installed (apt-get install chromium)"
)
def test_pages_render_their_figures_in_chromium(site, tmp_path):
    out, run, _ = site
    assert run.returncode == 0
    # the home page renders: header bar in the theme colour, text below it
    home = _screenshot(out / "index.html", tmp_path / "home.png", 900)
    assert home[:40].std() < 30 and home[:40].mean() < 200, "no header bar"
    assert (home[100:] < 128).all(axis=2).mean() > 0.005, "no text on the home page"
    for nb in NOTEBOOKS:
        page = out / "examples" / nb.stem / "index.html"
        html = page.read_text()
        heights = _png_heights(html)
        expected = len(heights)
        probe = page.with_name("figures-only.html")
        probe.write_text(html.replace("</head>", FIGURES_ONLY, 1))
        shot = _screenshot(probe, tmp_path / f"{nb.stem}.png", sum(heights) + 60 * expected + 300)
        frames = _frames(shot)
        assert len(frames) == expected, (
            f"{nb.name}: {expected} figures in the HTML, {len(frames)} rendered"
        )
        for i, (top, bottom, left, right) in enumerate(frames):
            plot = shot[top:bottom, left:right]
            assert plot.shape[0] > 100 and plot.shape[1] > 100, f"{nb.name}: figure {i} too small"
            ink = (plot < 200).any(axis=2).mean()  # lines, text, markers: not background
            assert 0.01 < ink < 0.9, f"{nb.name}: figure {i} is blank or solid (ink {ink:.3f})"
            assert np.ptp(plot.reshape(-1, 3), axis=0).max() > 100, f"{nb.name}: figure {i} flat"

"""MkDocs hooks of the tribojax site: executed notebooks, the generated API reference and the
docstring check.

- Notebooks. `notebooks/*.ipynb` are stored without outputs. The site shows executed copies kept
  in a staging folder (`build/docs-staged/examples/`, git-ignored). A staged copy is fresh when
  its recorded key (a hash of the notebook and of the package sources) matches; otherwise
  `mkdocs build` executes the notebook here, once, with nbclient. The test suite
  (`tests/test_docs.py`) executes each notebook as a test and stages it, so the build that
  follows executes nothing. A cell that raises fails the build, naming notebook and cell.
- API reference. One page per area, generated from the names `tribojax/__init__.pyi` and
  `tribojax/discovery/__init__.py` re-export (`from .x import Name as Name`), each rendered by
  mkdocstrings.
- Docstrings. A public name without a docstring is a warning, so `mkdocs build --strict` fails.
"""

from __future__ import annotations

import ast
import hashlib
import logging
import os
import re
from pathlib import Path

from mkdocs.exceptions import PluginError
from mkdocs.plugins import event_priority
from mkdocs.structure.files import File

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "src" / "tribojax"
NOTEBOOK_DIR = REPO / "notebooks"
STAGE = REPO / "build" / "docs-staged"  # staged notebooks live under STAGE / "examples"
EXAMPLES = "examples"
CELL_TIMEOUT_S = 600
# Figures go inline into the executed copy (the kernel would inherit MPLBACKEND=Agg from a test
# environment and then keep no figure); part of the staged copy's key.
MPL_BACKEND = "module://matplotlib_inline.backend_inline"
ANSI_ESCAPE = re.compile(r"\x1b\[[0-9;]*m")  # IPython colours its tracebacks

log = logging.getLogger("mkdocs.hooks.tribojax")

# API pages: (page, title, home subpackages of the names it lists, introduction)
API_PAGES = [
    (
        "contact",
        "Contact",
        ("_contact",),
        "Materials, fractal surface, asperity laws and the "
        "contact model of wang2022 Sections 2–3 (Eqs 1–24, 26, 28).",
    ),
    (
        "roughness",
        "Surfaces",
        ("_roughness",),
        "Topography records and readers, fractal "
        "estimates of D and G, seeded surface synthesis (wang2022 Eq 1, wu2015 Eq 3).",
    ),
    (
        "friction",
        "Friction elements",
        ("_friction",),
        "LuGre and pre-slip LuGre (wang2022 "
        "Eqs 25, 27), Jenkins and Mindlin (wu2015 Eqs 1–2), the Iwan bank, 2D elastic dry "
        "friction.",
    ),
    (
        "dynamics",
        "Dynamics",
        ("_dynamics",),
        "Stage profiles, slip simulation, harmonic "
        "balance, multi-harmonic balance, continuation and structures with friction contacts.",
    ),
    (
        "io",
        "Data and records",
        ("_io", "_tables", "_decimate"),
        "Published tables, slip runs, hysteresis loops, record reduction, atomic writes.",
    ),
    (
        "fit",
        "Fitting and sensitivity",
        ("_fit", "_model", "_predict", "_sensitivity"),
        "The one least-squares engine, the record models that fit, predict and discover share "
        "(slip runs, loops), the fits built on them, fitted models saved, loaded and evaluated "
        "on other records (`load_model`, `predict`), and sensitivities.",
    ),
    (
        "batch",
        "Many records",
        ("_batch",),
        "`tribojax.batch`: the `fit`, `discover` and `predict` commands on many records over a "
        "Dask cluster, one table row per record (the guide page Many records).",
    ),
    (
        "reproduce",
        "Reproduction and presets",
        ("_reproduce", "_presets", "_limits", "_results", "_sweep", "_chain", "_cache", "_xla"),
        "The papers' constants, the reproduced tables, the fits of wang2022's measured slips, "
        "result codes, sweeps, and the process choices an application makes (compilation "
        "cache, one-kernel loops).",
    ),
]
DISCOVERY_PAGE = (
    "discovery",
    "Discovery",
    "`tribojax.discovery`: baselines, named effects, region tests and the greedy discovery loop.",
)


# -- notebooks ---------------------------------------------------------------------------------


def source_key(notebook: Path) -> str:
    """Hash of the notebook and of every package source: a staged copy with another key is
    stale."""
    h = hashlib.sha256(notebook.read_bytes())
    h.update(MPL_BACKEND.encode())
    for path in sorted([*PACKAGE.rglob("*.py"), *PACKAGE.rglob("*.pyi")]):
        h.update(path.relative_to(PACKAGE).as_posix().encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def staged_path(notebook: Path) -> Path:
    """Where the executed copy of `notebook` is staged."""
    return STAGE / EXAMPLES / notebook.name


def staged_fresh(notebook: Path) -> bool:
    """True if the staged copy of `notebook` exists and was executed from the current sources."""
    import nbformat

    path = staged_path(notebook)
    if not path.exists():
        return False
    try:
        nb = nbformat.read(path, as_version=4)
    except Exception:  # a truncated or foreign file: execute again
        return False
    return nb.metadata.get("tribojax_docs", {}).get("source_key") == source_key(notebook)


class NotebookError(Exception):
    """A notebook cell raised; the message names the notebook and the cell's error."""


def execute_notebook(notebook: Path) -> Path:
    """Run `notebook` top to bottom in a fresh "python3" kernel (from the notebooks folder, with
    figures inline) and stage the executed copy; its path. NotebookError if a cell raises (the
    stale staged copy is removed)."""
    import nbclient
    import nbformat

    key = source_key(notebook)
    target = staged_path(notebook)
    nb = nbformat.read(notebook, as_version=4)
    client = nbclient.NotebookClient(
        nb,
        kernel_name="python3",
        timeout=CELL_TIMEOUT_S,
        resources={"metadata": {"path": str(NOTEBOOK_DIR)}},
    )
    env = dict(os.environ, MPLBACKEND=MPL_BACKEND)  # the kernel is a subprocess
    try:
        client.execute(cwd=str(NOTEBOOK_DIR), env=env)
    except nbclient.exceptions.CellExecutionError as err:
        target.unlink(missing_ok=True)
        message = ANSI_ESCAPE.sub("", str(err))
        raise NotebookError(f"{notebook.name}: a cell raised\n{message}") from None
    nb.metadata["tribojax_docs"] = {"source_key": key}
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_suffix(".tmp")
    nbformat.write(nb, tmp)
    tmp.replace(target)
    return target


def notebooks() -> list[Path]:
    """The notebooks of the site, in order."""
    return sorted(NOTEBOOK_DIR.glob("*.ipynb"))


# -- public names ------------------------------------------------------------------------------


def reexports(init: Path) -> list[tuple[str, str]]:
    """(public name, home module relative to the package) of each `from .m import X as X`."""
    out = []
    body = []
    for node in ast.parse(init.read_text()).body:  # top level and `if TYPE_CHECKING:` blocks
        body += node.body if isinstance(node, ast.If) else [node]
    for node in body:
        if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module:
            for alias in node.names:
                name = alias.asname or alias.name
                if not name.startswith("_"):
                    out.append((name, node.module))
    return out


def public_names() -> dict[str, list[str]]:
    """Page name -> the dotted public names it documents."""
    pages = {page: [] for page, *_ in API_PAGES}
    for name, module in reexports(PACKAGE / "__init__.pyi"):
        top = module.split(".")[0]
        page = next((p for p, _, homes, _ in API_PAGES if top in homes), None)
        if page is None:
            raise PluginError(f"tribojax.{name} comes from {module}, which no API page covers")
        pages[page].append(f"tribojax.{name}")
    pages[DISCOVERY_PAGE[0]] = [
        f"tribojax.discovery.{name}" for name, _ in reexports(PACKAGE / "discovery" / "__init__.py")
    ]
    return pages


def missing_docstrings(names) -> list[str]:
    """The names (dotted) whose object has no docstring, as griffe (and mkdocstrings) see it."""
    import griffe

    package = griffe.load(
        "tribojax", search_paths=[str(REPO / "src")], resolve_aliases=True, resolve_external=False
    )
    missing = []
    for dotted in names:
        obj = package[dotted.removeprefix("tribojax.")]
        target = obj.final_target if obj.is_alias else obj
        if target.docstring is None or not target.docstring.value.strip():
            missing.append(dotted)
    return missing


def api_page(title: str, intro: str, names: list[str]) -> str:
    lines = [f"# {title}", "", intro, ""]
    for dotted in sorted(names, key=lambda n: n.rsplit(".", 1)[1].lower()):
        lines += [f"::: {dotted}", ""]
    return "\n".join(lines)


# -- MkDocs events -----------------------------------------------------------------------------


@event_priority(100)  # before mkdocs-jupyter wraps the notebooks
def on_files(files, config):
    for notebook in notebooks():
        if not staged_fresh(notebook):
            log.info("executing %s (no fresh staged copy)", notebook.name)
            try:
                execute_notebook(notebook)
            except NotebookError as err:
                raise PluginError(str(err)) from None
        files.append(
            File(
                f"{EXAMPLES}/{notebook.name}",
                str(STAGE),
                config["site_dir"],
                config["use_directory_urls"],
            )
        )
    pages = public_names()
    for name in missing_docstrings([n for group in pages.values() for n in group]):
        log.warning(
            "%s has no docstring: every public name needs one (what, units, paper and equation)",
            name,
        )
    for page, title, _, intro in API_PAGES:
        files.append(
            File.generated(config, f"api/{page}.md", content=api_page(title, intro, pages[page]))
        )
    page, title, intro = DISCOVERY_PAGE
    files.append(
        File.generated(config, f"api/{page}.md", content=api_page(title, intro, pages[page]))
    )
    return files

"""The documentation's sources, cheaply (the fast tier): every notebook is valid and its code
parses, every docs page's Python parses, their imports resolve and every `tj.NAME` they use is a
public name; the site's navigation names existing pages. Executing the notebooks and building
the site is the second tier (tests/test_docs.py)."""

import ast
import importlib
import importlib.util
import re
from pathlib import Path

import pytest
import yaml

import tribojax as tj

nbformat = pytest.importorskip("nbformat")

REPO = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((REPO / "notebooks").glob("*.ipynb"))
PAGES = sorted((REPO / "docs").glob("*.md"))
FENCE = re.compile(r"^```python\n(.*?)^```", re.M | re.S)


def _cells(path: Path) -> list[str]:
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    # IPython magics and shell lines are not Python
    keep = lambda line: not line.lstrip().startswith(("%", "!"))  # noqa: E731
    code = [c.source for c in nb.cells if c.cell_type == "code"]
    return ["\n".join(filter(keep, source.splitlines())) for source in code]


def _problems(code: str, where: str) -> list[str]:
    """What in `code` does not parse, import or name a public tribojax name."""
    try:
        tree = ast.parse(code)
    except SyntaxError as err:
        return [f"{where}: line {err.lineno}: {err.msg}"]
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [
                f"{where}: no module {a.name}"
                for a in node.names
                if importlib.util.find_spec(a.name.split(".")[0]) is None
            ]
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            try:
                module = importlib.import_module(node.module)
            except ImportError as err:
                out.append(f"{where}: {err}")
                continue
            for a in node.names:
                if a.name != "*" and not hasattr(module, a.name):
                    try:
                        importlib.import_module(f"{node.module}.{a.name}")
                    except ImportError:
                        out.append(f"{where}: {node.module} has no {a.name}")
        elif (
            isinstance(node, ast.Attribute)
            and isinstance(node.value, ast.Name)
            and node.value.id == "tj"
            and node.attr not in tj.__all__
        ):
            out.append(f"{where}: tj.{node.attr} is not a public name")
    return out


def test_there_are_sources():
    assert len(NOTEBOOKS) >= 8 and len(PAGES) >= 10


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_is_valid_and_its_code_parses_and_imports(path):
    cells = _cells(path)
    assert cells, path.name
    problems = [p for i, c in enumerate(cells) for p in _problems(c, f"{path.name} cell {i}")]
    assert problems == []


def test_docs_pages_and_readme_python_blocks_parse_and_import():
    problems = []
    for page in [*PAGES, REPO / "README.md"]:
        for i, block in enumerate(FENCE.findall(page.read_text(encoding="utf-8"))):
            problems += _problems(block, f"{page.name} block {i}")
    assert problems == []


def test_the_checks_catch_what_they_claim():
    assert _problems("x = (", "a") and _problems("import no_such_module_xyz", "b")
    assert _problems("from tribojax import no_such_name", "c")
    assert _problems("import tribojax as tj\ntj.no_such_name", "d")
    assert _problems("import tribojax as tj\ntj.FractalContact", "e") == []


def _nav_files(nav) -> list[str]:
    if isinstance(nav, str):
        return [nav]
    if isinstance(nav, dict):
        return [f for v in nav.values() for f in _nav_files(v)]
    return [f for v in nav for f in _nav_files(v)]


def test_site_navigation_names_existing_pages():
    config = yaml.safe_load((REPO / "mkdocs.yml").read_text(encoding="utf-8"))
    files = _nav_files(config["nav"])
    assert "index.md" in files
    generated = ("api/", "examples/")  # written by docs/hooks.py at build time
    missing = [f for f in files if not f.startswith(generated) and not (REPO / "docs" / f).exists()]
    assert missing == []
    assert {f"examples/{nb.name}" for nb in NOTEBOOKS} <= set(files)  # every notebook a page

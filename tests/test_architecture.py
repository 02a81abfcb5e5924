"""The package's layout rules (issue 13): no import cycles, no hidden imports, small modules.

Read from the source with `ast` (nothing is imported), so a violation names the file and line:
- no cycle in the graph of module imports inside `tribojax`;
- no import of a `tribojax` module inside a function (such imports hid cycles before);
- no private name (`_x`) imported from another subpackage (make it public in its package or
  move it);
- every module at most 400 lines as the plain formatter lays it out (`ruff format`, checked
  here: no hand-packed lines, so the limit measures concepts, not layout);
- every third-party module imported at run time is a declared dependency (optional ones only
  inside the optional-dependency guards);
- imports go down the layer order `LAYERS` (issue 29), never up;
- the command line and the record reduction ask a record (`AbstractRecord`: its `kind`, its
  methods), never test its class with `isinstance` (issue 29).
"""

import ast
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "tribojax"
MAX_LINES = 400
# optional dependencies: allowed only in these modules (each import guarded there)
OPTIONAL = {
    "matplotlib": {"tribojax._plot"},
    "SurfaceTopography": {"tribojax._roughness._topography"},
    "distributed": {"tribojax._batch._run", "tribojax._batch._task"},
    "dask": {"tribojax._batch._run"},
}
# distribution name -> import name where they differ
IMPORT_NAMES = {"jax": {"jax", "jaxlib"}}
# The layer order, lowest first: a module imports modules of its own layer and of the layers
# below it, never of a layer above. Each unit is a subpackage or top-level module of tribojax
# ("" is tribojax/__init__.py). Within a layer any direction goes (cycles are caught above).
# - foundation: float64 switch, the compilation cache and stored traces (`_export`), validation,
#   result codes, the matplotlib guard, the validating CSV reader with the bundled published
#   tables (`_tables`), the papers' constants (`_presets`) and the shared names and budgets
#   (`_limits`; these two import nothing), the threads that run independent fits side by side
#   (`_parallel`);
# - physics: contact (with the papers' preset pairs and load laws), surfaces, friction elements,
#   dynamics: no records, no fits;
# - model chain: wang2022's one path parameters → contact → element → phase slips (`_chain`);
# - model analyses: sweeps and sensitivities of the model, which need no records;
# - records: user records and files (`_io`);
# - fit engine: the one least-squares engine, its result and statistics, solver, noise model and
#   measures, and nothing that knows a model (`_fit`);
# - record models: the one model of each record kind, its fit, saved models, the fits built on
#   them (a surface from slip runs at several loads) and the separately named fits (history
#   elements, the steady friction law) (`_model`), strictly above the engine;
# - record reduction (`_decimate`), which states its noise with the fit's noise model;
# - paper studies: the reproduced tables and the fits of wang2022's measured slips (`_reproduce`);
# - discovery; prediction with saved models (`_predict`: rebuilds a model with its discovered
#   effects); the public re-exports (tribojax/__init__.py); the command line, which nothing
#   else imports but the batch runner above it (`_batch`: the commands on many records).
LAYERS = (
    (
        "foundation",
        {
            "_precision",
            "_cache",
            "_export",
            "_checks",
            "_results",
            "_plot",
            "_tables",
            "_presets",
            "_limits",
            "_parallel",
            "_xla",
        },
    ),
    ("physics", {"_contact", "_roughness", "_friction", "_dynamics"}),
    ("model chain", {"_chain"}),
    ("model analyses", {"_sweep", "_sensitivity"}),
    ("records", {"_io"}),
    ("fit engine", {"_fit"}),
    ("record models", {"_model"}),
    ("record reduction", {"_decimate"}),
    ("paper studies", {"_reproduce"}),
    ("discovery", {"discovery"}),
    ("prediction", {"_predict"}),
    ("public API", {""}),
    ("command line", {"_cli", "__main__"}),
    ("batch", {"_batch"}),
)
LAYER_OF = {unit: (i, name) for i, (name, units) in enumerate(LAYERS) for unit in units}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in sorted(SRC.rglob("*.py"))}


def _target(mod: str, node: ast.ImportFrom, is_package: bool) -> str:
    if node.level == 0:
        return node.module or ""
    base = mod.split(".") if is_package else mod.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _subpackage(mod: str) -> str:
    parts = mod.split(".")
    return parts[1] if len(parts) > 2 else ""


def _unit(mod: str) -> str:
    """The subpackage or top-level module of `mod` ("" for tribojax itself): what LAYERS orders."""
    parts = mod.split(".")
    return parts[1] if len(parts) > 1 else ""


def _scan():
    edges, hidden, private, external, sites = {}, [], [], {}, []
    for mod, path in MODULES.items():
        tree = ast.parse(path.read_text(), filename=str(path))
        top = {id(node) for node in tree.body}
        # the imports of an `if TYPE_CHECKING:` block at module level are declarations (never
        # run): tribojax/__init__.py's table of public names
        for node in tree.body:
            if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING":
                top |= {id(child) for child in node.body}
        is_package = path.name == "__init__.py"
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    name = alias.name.split(".")[0]
                    if name == "tribojax":
                        if id(node) not in top:
                            hidden.append(f"{path}:{node.lineno}")
                        sites.append((path, node.lineno, mod, alias.name))
                    else:
                        external.setdefault(name, set()).add(mod)
                continue
            if not isinstance(node, ast.ImportFrom):
                continue
            target = _target(mod, node, is_package)
            if not target.startswith("tribojax"):
                external.setdefault(target.split(".")[0], set()).add(mod)
                continue
            if id(node) not in top:
                hidden.append(f"{path}:{node.lineno}")
            for alias in node.names:
                full = f"{target}.{alias.name}"
                dep = full if full in MODULES else target
                if dep != mod and dep in MODULES:
                    edges.setdefault(mod, set()).add(dep)
                    sites.append((path, node.lineno, mod, dep))
                name = alias.name
                if (
                    name.startswith("_")
                    and not name.startswith("__")
                    and full not in MODULES
                    and _subpackage(target) != _subpackage(mod)
                ):
                    private.append(f"{path}:{node.lineno} imports {name} from {target}")
    return edges, hidden, private, external, sites


EDGES, HIDDEN, PRIVATE, EXTERNAL, SITES = _scan()


def test_no_import_cycles():
    index, low, stack, on_stack, cycles = {}, {}, [], set(), []
    counter = [0]

    def visit(v):  # Tarjan's strongly connected components
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in EDGES.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
    for v in MODULES:
        if v not in index:
            visit(v)
    assert not cycles, f"import cycles: {cycles}"


# The command-line dispatcher imports a subcommand's module (and the library) only when it runs,
# so that `tribojax --help` and argument errors start without JAX (issue 31); a batch worker's
# record task likewise, after it has made the command's process settings (EQX_ON_ERROR is read
# when equinox is imported). Nothing else may.
DEFERRED = ("tribojax/_cli/_main.py:", "tribojax/_batch/_task.py:")


def test_no_function_level_imports_of_tribojax():
    hidden = [h for h in HIDDEN if not any(d in h.replace("\\", "/") for d in DEFERRED)]
    assert not hidden, f"imports of tribojax modules inside functions: {hidden}"


def test_the_command_line_parses_without_jax():
    # `tribojax --help`, `--version` and argument errors: no JAX, no numpy (a fresh interpreter)
    code = (
        "import sys\n"
        "from tribojax._cli._main import build_parser\n"
        "p = build_parser()\n"
        "for argv in (['fit', '--help'], ['contact'], ['--version'], ['frob']):\n"
        "    try:\n"
        "        p.parse_args(argv)\n"
        "    except SystemExit:\n"
        "        pass\n"
        "print(sorted(m for m in ('jax', 'numpy', 'equinox', 'scipy') if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stdout[-500:]


def test_no_private_names_across_subpackages():
    assert not PRIVATE, "\n".join(PRIVATE)


def test_every_module_is_in_a_layer():
    missing = sorted({_unit(mod) for mod in MODULES} - set(LAYER_OF))
    assert not missing, f"not in LAYERS (tests/test_architecture.py), place them: {missing}"


def test_imports_go_down_the_layers():
    """An import of a higher layer (e.g. physics reading `_io`, `_fit` importing `_reproduce`,
    anything but the command line importing `_cli`) fails with its file and line."""
    upward = []
    for path, lineno, mod, dep in SITES:
        if _unit(mod) not in LAYER_OF or _unit(dep) not in LAYER_OF:
            continue  # test_every_module_is_in_a_layer names it
        (low, low_name), (high, high_name) = LAYER_OF[_unit(mod)], LAYER_OF[_unit(dep)]
        if high > low:
            upward.append(f"{path}:{lineno}: {mod} ({low_name}) imports {dep} ({high_name})")
    assert not upward, "imports up the layer order (LAYERS):\n" + "\n".join(upward)


@pytest.mark.parametrize("mod", sorted(MODULES))
def test_module_size(mod):
    n = len(MODULES[mod].read_text().splitlines())
    assert n <= MAX_LINES, (
        f"{MODULES[mod]} has {n} lines (house limit {MAX_LINES}): cut it by concept"
    )


MARKER = re.compile(r"#\s*fmt:\s*(skip|off)")  # (spelled so that it does not match itself)
FORMATTED = ("src", "tests", "benchmarks", "fitting", "docs/hooks.py", "data/real/convert.py")


def test_code_is_laid_out_by_the_formatter():
    """`ruff format` (the test extras' version) leaves the code as it is: no formatter-skip
    packing that would hide a module's size."""
    proc = subprocess.run(
        [sys.executable, "-m", "ruff", "format", "--check", *FORMATTED],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    skips = [
        f"{p}:{i}"
        for root in FORMATTED
        for p in sorted((ROOT / root).rglob("*.py"))
        if (ROOT / root).is_dir()
        for i, line in enumerate(p.read_text().splitlines(), 1)
        if MARKER.search(line)
    ]
    assert not skips, f"formatter markers: {skips[:10]}"


def test_runtime_imports_are_declared():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    declared = set()
    for req in meta["dependencies"]:
        name = req.split(">")[0].split("=")[0].split("<")[0].split("[")[0].strip().lower()
        declared |= IMPORT_NAMES.get(name, {name})
    stdlib = set(sys.stdlib_module_names) | {"__future__"}
    undeclared, misplaced = [], []
    for name, users in sorted(EXTERNAL.items()):
        if name in stdlib or name.lower() in declared:
            continue
        if name in OPTIONAL:
            extra = users - OPTIONAL[name]
            if extra:
                misplaced.append(f"{name} imported in {sorted(extra)} (only {OPTIONAL[name]})")
            continue
        undeclared.append(f"{name} (in {sorted(users)})")
    assert not undeclared, f"runtime imports not declared in pyproject.toml: {undeclared}"
    assert not misplaced, misplaced


# modules that treat the record kinds differently through the records' interface (issue 29)
RECORD_DISPATCH = [m for m in MODULES if m.startswith("tribojax._cli.")] + ["tribojax._decimate"]


def _record_classes() -> set[str]:
    """AbstractRecord and the record classes of `_io` that subclass it (read from the source)."""
    names = {"AbstractRecord"}
    for path in sorted((SRC / "_io").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.ClassDef) and any(
                isinstance(b, ast.Name) and b.id == "AbstractRecord" for b in node.bases
            ):
                names.add(node.name)
    return names


def test_no_isinstance_dispatch_on_records():
    """`isinstance`/`issubclass` on a record class in the command line or `_decimate` fails with
    its file and line: dispatch on `record.kind` or a method of the record instead."""
    records = _record_classes()
    assert {"SlipRun", "HysteresisLoop", "FrictionCurve", "FrictionTransient"} <= records
    found = []
    for mod in RECORD_DISPATCH:
        path = MODULES[mod]
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            func = getattr(node, "func", None)
            if getattr(func, "id", None) not in ("isinstance", "issubclass") or len(node.args) < 2:
                continue
            named = {getattr(n, "id", getattr(n, "attr", None)) for n in ast.walk(node.args[1])}
            if named & records:
                found.append(f"{path}:{node.lineno}: {func.id} on {sorted(named & records)}")
    assert not found, "isinstance dispatch on records:\n" + "\n".join(found)


def test_no_classes_made_at_runtime():
    """No class is made by a three-argument `type(...)` call in `src/` (issue 29: the table
    effects were): every effect and model is a class statement that a reader can find."""
    found = []
    for path in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if getattr(getattr(node, "func", None), "id", None) == "type" and len(node.args) == 3:
                found.append(f"{path}:{node.lineno}")
    assert not found, "classes made by type():\n" + "\n".join(found)

"""Traced programs kept on disk: `cached_jit`, `eqx.filter_jit` whose trace survives the process.

JAX's persistent cache skips XLA compilation in a new process but not tracing and lowering.
`cached_jit` exports the lowered program (`jax.export`, StableHLO) the first time a signature is
met and stores it beside the compilation cache (`export_dir`); a new process reads it back and
only compiles it. A stored program is used only under the same key (`_key`); a signature that
cannot be keyed, a program that cannot be exported (it leaves an empty `.refused` marker) or a
call under a trace runs through plain `eqx.filter_jit`. docs/performance.md (Stored traces) gives
the key in full, the file checks, the lock (`_LOWERING`) and the reasons.
"""

from __future__ import annotations

import functools
import hashlib
import os
import sys
import tempfile
import threading
from importlib import metadata
from pathlib import Path

import equinox as eqx
import jax
import numpy as np

from ._cache import export_dir
from ._checks import mode_jit, nan_mode

MAGIC = b"tribojax-export-2\n"  # then the key the file is stored under, a sha256, the payload
_PACKAGES = ("jax", "jaxlib", "equinox", "lineax", "optimistix", "diffrax", "numpy", "jaxtyping")
# code named in a key must be code the key versions: tribojax's (its source is hashed) or these
# packages' (their versions); a user's own function or class is not keyed (its source may change)
_VERSIONED = frozenset(("tribojax", "builtins", *_PACKAGES))
_ATOMS = (int, float, bool, str, bytes, complex, type(None), np.dtype, np.generic)


class _Unkeyable(Exception):
    pass


@functools.cache
def _environment() -> str:
    root = Path(__file__).parent
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes())
    versions = []
    for name in _PACKAGES:
        try:
            versions.append(f"{name}={metadata.version(name)}")
        except metadata.PackageNotFoundError:
            versions.append(f"{name}=?")
    return f"{h.hexdigest()}|{'|'.join(versions)}|{jax.default_backend()}"


def _atom(x) -> str:
    if isinstance(x, _ATOMS):
        return f"{type(x).__name__}:{x!r}"
    if isinstance(x, type):
        if not _versioned(x.__module__):
            raise _Unkeyable(x.__qualname__)
        return f"type:{x.__module__}.{x.__qualname__}"
    if isinstance(x, functools.partial):
        return f"partial({_atom(x.func)},{_atom(x.args)},{_atom(x.keywords)})"
    if isinstance(x, eqx.Module):  # a module of static values only (e.g. a diffrax adjoint)
        leaves, tree = jax.tree_util.tree_flatten(x)
        return f"{_structure(tree)}{_atom(tuple(leaves))}"
    named = _module_level(x)
    if named is not None:
        return named
    if isinstance(x, (tuple, list)):
        return f"{type(x).__name__}({','.join(_atom(v) for v in x)})"
    if isinstance(x, dict):
        return "dict(" + ",".join(f"{_atom(k)}={_atom(v)}" for k, v in x.items()) + ")"
    if type(x).__qualname__ == "_Missing" or isinstance(x, jax.ShapeDtypeStruct):  # equinox's
        return repr(x)
    raise _Unkeyable(type(x).__qualname__)


def _versioned(module) -> bool:
    return isinstance(module, str) and module.split(".")[0] in _VERSIONED


def _module_level(x) -> str | None:
    """'module.name' of a function or callable object bound at module level (so that its identity
    is its source): under its own name, or (an equinox wrapper that keeps no name) under a name
    in a tribojax module; None otherwise (a lambda, a closure, a built object)."""
    mod, name = getattr(x, "__module__", None), getattr(x, "__qualname__", None)
    if isinstance(mod, str) and isinstance(name, str) and "<" not in name:
        found = sys.modules.get(mod)
        for part in name.split("."):
            found = getattr(found, part, None)
        if found is x and _versioned(mod):
            return f"obj:{mod}.{name}"
    if not callable(x) or isinstance(name, str):  # named, but not bound under that name
        return None
    if id(x) not in _BOUND:
        where = next(
            (
                f"obj:{m}.{k}"
                for m, module in list(sys.modules.items())
                if m.startswith("tribojax.")
                for k, v in vars(module).items()
                if v is x
            ),
            None,
        )
        if where is None:
            return None
        _BOUND[id(x)] = (x, where)  # module-level, so alive anyway: its id is not reused
    return _BOUND[id(x)][1]


_BOUND: dict = {}


def _structure(treedef) -> str:
    data = treedef.node_data()
    children = ",".join(_structure(c) for c in treedef.children())
    if data is None:
        return "*" if treedef.num_leaves == 1 and not children else f"[{children}]"
    kind, aux = data
    return f"{_atom(kind)}<{_atom(aux)}>({children})"


def _trace_context() -> tuple:
    """What a trace depends on beyond its arguments: the settings that change how tribojax's code
    traces, and failures as NaN (`tribojax._checks.failures_as_nan`)."""
    c = jax.config
    return (
        c.jax_enable_x64,
        c.jax_numpy_rank_promotion,
        c.jax_numpy_dtype_promotion,
        c.jax_default_matmul_precision,
        nan_mode(),
    )


def _key(fn, treedef, static, leaves) -> str | None:
    if not _versioned(fn.__module__):
        return None
    try:
        s_leaves, s_tree = jax.tree_util.tree_flatten(static)
        text = "\n".join(
            [
                f"{fn.__module__}.{fn.__qualname__}",
                _environment(),
                repr(_trace_context()),
                _structure(treedef),
                _structure(s_tree),
                _atom(tuple(s_leaves)),
                ";".join(
                    f"{x.dtype}{list(x.shape)}{getattr(x, 'weak_type', False)}" for x in leaves
                ),
            ]
        )
    except _Unkeyable:
        return None
    return hashlib.sha256(text.encode()).hexdigest()


def _read(path: Path):
    """The program stored at `path`, or None (a miss) for a file that is not one, is filed under
    another key (its header names the key it was written for), or fails its checksum."""
    try:
        blob = path.read_bytes()
    except OSError:
        return None
    start = MAGIC + path.stem.encode()
    head = len(start) + 32
    if not blob.startswith(start) or len(blob) <= head:
        return None
    payload = blob[head:]
    if hashlib.sha256(payload).digest() != blob[len(start) : head]:
        return None
    try:
        return jax.export.deserialize(bytearray(payload))
    except Exception:  # noqa: BLE001 - an unreadable entry is a miss
        return None


def _write(path: Path, exported) -> None:
    """Store `exported` at `path`, or (None) an empty marker: this program cannot be exported, so
    the next process traces it once instead of twice."""
    try:
        payload = b"" if exported is None else bytes(exported.serialize())
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-")
        with os.fdopen(fd, "wb") as f:
            f.write(
                MAGIC + path.stem.encode() + hashlib.sha256(payload).digest() + payload
                if payload
                else b""
            )
        os.replace(tmp, path)
    except (OSError, ImportError):  # `flatbuffers` missing, or a read-only cache folder:
        pass  # the program is still used in this process


@functools.cache
def _lapack_calls() -> tuple:
    """The CPU LAPACK calls of this jaxlib, allowed in a stored program: jax.export refuses custom
    calls it does not guarantee across versions, but a stored program is only read back by the
    same jaxlib (its version is in the key). Host callbacks stay refused."""
    try:
        from jaxlib.cpu import _lapack

        names = sorted(_lapack.registrations()) if jax.default_backend() == "cpu" else []
    except (ImportError, AttributeError):
        names = []
    return tuple(jax.export.DisabledSafetyCheck.custom_call(n) for n in names)


def _export(fn, treedef, static, leaves):
    def flat(*xs):
        return fn(*eqx.combine(jax.tree_util.tree_unflatten(treedef, xs), static))

    specs = [
        jax.ShapeDtypeStruct(x.shape, x.dtype, weak_type=getattr(x, "weak_type", False))
        for x in leaves
    ]
    try:
        return jax.export.export(jax.jit(flat), disabled_checks=_lapack_calls())(*specs)
    except Exception:  # noqa: BLE001 - not exportable (a host callback): filter_jit traces it
        return None


_LOWERING = threading.RLock()


def _matches(exported, leaves) -> bool:
    """Whether a stored program takes exactly these arrays (shapes and dtypes)."""
    avals = exported.in_avals
    return len(avals) == len(leaves) and all(
        a.shape == x.shape and a.dtype == x.dtype for a, x in zip(avals, leaves)
    )


def _program(fn, treedef, static, leaves, stem: Path):
    """The stored program at `stem` (read, or exported and written), compiled for `leaves`' shapes;
    None if refused. Holds `_LOWERING` throughout."""
    path, refused = stem.with_suffix(".jaxexp"), stem.with_suffix(".refused")
    with _LOWERING:
        if refused.exists():
            return None
        exported = _read(path)
        if exported is not None and not _matches(exported, leaves):
            exported = None  # not this signature's program: traced again and rewritten
        if exported is None:
            exported = _export(fn, treedef, static, leaves)
            _write(path if exported is not None else refused, exported)
        return None if exported is None else jax.jit(exported.call).lower(*leaves).compile()


def cached_jit(fn):
    """`eqx.filter_jit(fn)` whose traced program is also stored on disk (see the module doc);
    `fn` must be a module-level function returning arrays in tuples, lists or dicts."""
    jitted = mode_jit(fn)
    programs: dict = {}
    locks: dict = {}
    keys: dict = {}  # signature -> key: the key's hashing once per signature, not per call

    @functools.wraps(fn)
    def call(*args):
        folder = export_dir()
        dyn, static = eqx.partition(args, eqx.is_array)
        leaves, treedef = jax.tree_util.tree_flatten(dyn)
        if folder is None or any(isinstance(x, jax.core.Tracer) for x in leaves):
            return jitted(*args)
        # the signature as JAX's and equinox's own jit caches compare it (trace context,
        # structures and static values by equality, arrays by shape and dtype), and the folder
        s_leaves, s_tree = jax.tree_util.tree_flatten(static)
        sig = (
            folder,
            _trace_context(),
            treedef,
            s_tree,
            *((type(v), v) for v in s_leaves),
            *((x.shape, x.dtype, getattr(x, "weak_type", False)) for x in leaves),
        )
        try:
            key = (
                keys[sig]
                if sig in keys
                else keys.setdefault(sig, _key(fn, treedef, static, leaves))
            )
        except TypeError:  # a static value that cannot be hashed: keyed every call
            key = _key(fn, treedef, static, leaves)
        if key is None:
            return jitted(*args)
        if key not in programs:
            # threads meeting a new program wait for one export and compile
            with locks.setdefault(key, threading.Lock()):
                if key not in programs:
                    program = _program(fn, treedef, static, leaves, folder / key)
                    out = jitted(*args) if program is None else program(*leaves)
                    programs[key] = program
                    return out
        program = programs[key]
        return jitted(*args) if program is None else program(*leaves)

    call.programs, call.jitted = programs, jitted  # inspected by the tests
    return call

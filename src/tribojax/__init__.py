"""tribojax: rough-surface contact, friction and slip models in JAX.

Importing tribojax is cheap: a public name is imported from its module when first used (PEP 562
`__getattr__`), so the command line starts without JAX. The names and their homes are the imports
of the type stub `__init__.pyi` (read by type checkers, the API docs and, parsed once, by
`__getattr__`, as SPEC 1's `lazy_loader.attach_stub` does).

The one setting tribojax changes in a process is `jax_enable_x64` (float64 is a correctness
requirement): on at import, in an imported JAX at once or, for a JAX imported later, through
`JAX_ENABLE_X64=1`, so that arrays made before the first use are float64 too. A user who set
`JAX_ENABLE_X64` to a false value is not overruled: every model entry point then refuses to run in
float32 (`tribojax._precision.ensure_x64`). Compilation cache and XLA options are the application's
choice: `use_compilation_cache`, `use_one_kernel` (the `tribojax` command makes both for itself).
"""


def _x64() -> None:
    import os
    import sys

    chosen = os.environ.get("JAX_ENABLE_X64", "").strip().lower()
    if chosen in ("0", "false", "no", "off"):
        return  # the user's explicit choice: refused at first use, not overruled
    if "jax" in sys.modules:  # already imported: switch it now (JAX reads the variable on import)
        sys.modules["jax"].config.update("jax_enable_x64", True)
    else:
        os.environ["JAX_ENABLE_X64"] = "1"


def _stub_exports() -> dict:
    """public name -> (home module, name there): the stub's `from ... import ... as ...` lines."""
    import ast
    from pathlib import Path

    out = {}
    stub = Path(__file__).with_suffix(".pyi")
    for node in ast.parse(stub.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.ImportFrom) and node.module is not None:
            for alias in node.names:
                out[alias.asname or alias.name] = (node.module, alias.name)
    return out


_x64()
_EXPORTS = _stub_exports()
_SUBPACKAGES = ("discovery",)
__all__ = sorted([*_EXPORTS, *_SUBPACKAGES, "__version__"])


def __getattr__(name: str):
    import importlib

    if name in _SUBPACKAGES:
        return importlib.import_module(f"{__name__}.{name}")
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            value = version("tribojax")
        except PackageNotFoundError:  # running from a source tree without installation
            value = "0.0.0"
    else:
        try:
            module, attr = _EXPORTS[name]
        except KeyError:
            raise AttributeError(f"module 'tribojax' has no attribute {name!r}") from None
        value = getattr(importlib.import_module(f"{__name__}.{module}"), attr)
    globals()[name] = value  # later lookups skip __getattr__
    return value


def __dir__() -> list[str]:
    return list(__all__)

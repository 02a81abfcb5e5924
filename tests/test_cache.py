"""Start-up and the persistent compilation cache (issue 31), each in a fresh interpreter.

- the fit engine's programs hold no host callback, so JAX caches them: a second process finds
  them on disk and gives the same numbers to the last digit;
- `TRIBOJAX_CACHE=off`, `TRIBOJAX_CACHE_DIR` and a user's own JAX cache folder are respected;
- an entry that cannot be read (truncated) is compiled again, never used;
- `import tribojax` does not import JAX until a name is used, and still gives float64 arrays;
- the dependency floors in pyproject.toml are met by what the suite runs with.
"""

import json
import os
import re
import subprocess
import sys
import tomllib
from importlib.metadata import version
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

# a small slip-run fit; prints its numbers and which engine programs came from the cache
_FIT = r"""
import json, logging, sys
hits = []
class H(logging.Handler):
    def emit(self, rec):
        m = rec.getMessage()
        if "Persistent compilation cache hit" in m or "uses host callbacks" in m:
            hits.append(m.split("'")[1] + (" callback" if "callback" in m else " hit"))
h = H(); h.setLevel(logging.DEBUG)
log = logging.getLogger("jax._src.compiler"); log.addHandler(h); log.setLevel(logging.DEBUG)
import tribojax as tj
import jax
el = tj.PreSlipLuGre(F_s=1.1, K_tau=2.0e7, C_tau=150.0)
run = tj.synthetic_slip_run(el, n=461, noise=0.3e-9, seed=3)
fit = tj.fit_slip_run(run, alpha=1.0)
print(json.dumps({"values": [float(v) for v in fit.values], "converged": bool(fit.converged),
                  "programs": sorted(set(hits)),
                  "cache_dir": jax.config.jax_compilation_cache_dir}))
"""


def _python(code, env_extra, tmp_path):
    env = {k: v for k, v in os.environ.items()
           if k not in ("TRIBOJAX_CACHE", "TRIBOJAX_CACHE_DIR", "JAX_COMPILATION_CACHE_DIR")}
    env.update(env_extra)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         cwd=tmp_path, timeout=600)  # fmt: skip
    assert out.returncode == 0, out.stderr[-3000:]
    return out


def _fit(env_extra, tmp_path):
    return json.loads(_python(_FIT, env_extra, tmp_path).stdout.strip().splitlines()[-1])


def test_fit_programs_are_cached_and_give_the_same_numbers(tmp_path):
    env = {"TRIBOJAX_CACHE_DIR": str(tmp_path / "cache")}
    first = _fit(env, tmp_path)
    assert first["cache_dir"] == str(tmp_path / "cache")
    assert first["converged"]
    # the engine's two programs (the record generator's simulation, throw=True, has callbacks)
    engine = ("jit__solve_jit", "jit__value_and_jacobian_jit")
    assert not [p for p in first["programs"] if p.startswith(engine)], first["programs"]
    entries = [p for p in (tmp_path / "cache").iterdir() if p.name.startswith(engine)]
    assert len(entries) >= 2, sorted(p.name for p in (tmp_path / "cache").iterdir())
    # a truncated entry (a killed writer) is compiled again, with a warning, never used
    bad = next(p for p in entries if p.name.startswith(engine[1]))
    bad.write_bytes(bad.read_bytes()[: bad.stat().st_size // 2])
    second = _fit(env, tmp_path)
    assert f"{engine[0]} hit" in second["programs"], second
    assert f"{engine[1]} hit" not in second["programs"], second
    assert second["values"] == first["values"]  # bit for bit: the cached program is the same


def test_cache_settings_are_respected(tmp_path):
    code = ("import tribojax as tj, jax; tj.FractalSurface; "
            "print(jax.config.jax_compilation_cache_dir)")
    off = _python(code, {"TRIBOJAX_CACHE": "off"}, tmp_path).stdout.split()[-1]
    assert off == "None"
    users = _python(code, {"JAX_COMPILATION_CACHE_DIR": str(tmp_path / "mine")}, tmp_path)
    assert users.stdout.split()[-1] == str(tmp_path / "mine")  # the user's own folder stays
    home = _python(code, {"XDG_CACHE_HOME": str(tmp_path / "xdg")}, tmp_path).stdout.split()[-1]
    if sys.platform.startswith("linux"):
        assert home == str(tmp_path / "xdg" / "tribojax" / "jax")


def test_import_is_lazy_and_arrays_are_float64(tmp_path):
    code = (
        "import sys, tribojax as tj\n"
        "print('jax' in sys.modules)\n"
        "import jax.numpy as jnp\n"
        "print(jnp.linspace(0.0, 1.0, 3).dtype)\n"
        "print(type(tj.PreSlipLuGre).__name__, 'jax' in sys.modules)\n"
        "print(sorted(set(dir(tj)) >= {'fit_slip_run', 'discovery', '__version__'} and ['ok']))\n"
    )
    lines = _python(code, {}, tmp_path).stdout.split("\n")
    assert lines[0] == "False"
    assert lines[1] == "float64"  # a jax imported after tribojax works in float64
    assert lines[2].endswith("True")
    assert lines[3] == "['ok']"
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        import tribojax

        tribojax.no_such_name  # noqa: B018


def test_dependency_floors_are_met():
    deps = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["dependencies"]
    for dep in deps:
        spec = dep.split(";")[0].strip()
        name, floor = re.fullmatch(r"([A-Za-z0-9_.-]+)>=([0-9.]+)", spec).groups()
        have = tuple(int(x) for x in re.findall(r"\d+", version(name))[:3])
        need = tuple(int(x) for x in floor.split("."))
        assert have >= need, f"{name} {version(name)} is below the floor {floor}"

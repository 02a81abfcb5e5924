"""Start-up and the persistent compilation cache, each in a fresh interpreter.

- the fit engine's programs hold no host callback, so their traces are stored (`jax.export`) and
  JAX caches their compilation: a second process reads both from disk and gives the same numbers
  to the last digit; a corrupt stored trace is traced again, never used;
- the cache is the application's choice (`use_compilation_cache`): off without it; with it,
  `TRIBOJAX_CACHE=off`, `TRIBOJAX_CACHE_DIR`, a user's own JAX cache folder and minimum compile
  time are respected, and everything stored stays inside the chosen folder;
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

# a small loop fit through the record model (`fit_loop(model="history")`: the engine's solve and
# Jacobian programs, as every fit; a slip run's ODE costs 2.4x the compile time here: 24 s cold
# against 10 s); prints its numbers and which engine programs came from the cache
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
tj.use_compilation_cache()
import tribojax._export as E
found = []
_read = E._read
E._read = lambda path: found.append(_read(path) is not None) or _read(path)
import dataclasses
import numpy as np
loop = tj.synthetic_loop(tj.Jenkins(0.3, 10.0, 1.0e6), 6e-6, 2 * np.pi * 10.0, cycles=3,
                         samples_per_cycle=120)
loop = dataclasses.replace(loop, f=loop.f + np.random.default_rng(3).normal(0.0, 0.01, loop.f.size))
fit = tj.fit_loop(loop, model="history")
print(json.dumps({"values": [float(v) for v in fit.values], "converged": bool(fit.converged),
                  "programs": sorted(set(hits)), "read": sum(found), "missed": found.count(False),
                  "cache_dir": jax.config.jax_compilation_cache_dir}))
"""


def _python(code, env_extra, tmp_path):
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("TRIBOJAX_CACHE", "TRIBOJAX_CACHE_DIR", "JAX_COMPILATION_CACHE_DIR")
    }
    env.update(env_extra)
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    return out


def _fit(env_extra, tmp_path):
    return json.loads(_python(_FIT, env_extra, tmp_path).stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_fit_programs_are_cached_and_give_the_same_numbers(tmp_path):
    env = {"TRIBOJAX_CACHE_DIR": str(tmp_path / "cache")}
    first = _fit(env, tmp_path)
    assert first["cache_dir"] == str(tmp_path / "cache" / "jax")
    assert first["converged"] and first["read"] == 0 and first["missed"] >= 2, first
    # the engine's two programs (solve, value and Jacobian) are stored as traces and, compiled
    # from them (`jit_call`), in JAX's cache; no program of theirs holds a host callback
    stored = sorted((tmp_path / "cache" / "export").glob("*.jaxexp"))
    assert len(stored) == first["missed"], stored
    assert not [p for p in first["programs"] if p.startswith("jit_call ") and "callback" in p]
    second = _fit(env, tmp_path)
    assert second["read"] == len(stored) and second["missed"] == 0, second
    assert "jit_call hit" in second["programs"], second
    assert second["values"] == first["values"]  # bit for bit: the stored program is the same
    # a corrupt stored trace (a flipped byte) fails its checksum: traced again, never used
    blob = bytearray(stored[0].read_bytes())
    blob[-10] ^= 0xFF
    stored[0].write_bytes(bytes(blob))
    third = _fit(env, tmp_path)
    assert third["missed"] == 1 and third["read"] == len(stored) - 1, third
    assert third["values"] == first["values"]
    assert stored[0].read_bytes() != bytes(blob)  # written again
    # a truncated compiled entry (a killed writer) is compiled again, with a warning, never used
    compiled = [p for p in (tmp_path / "cache" / "jax").iterdir() if p.name.startswith("jit_call")]
    for p in compiled:
        p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])
    fourth = _fit(env, tmp_path)
    assert "jit_call hit" not in fourth["programs"] and fourth["values"] == first["values"]


def test_cache_settings_are_respected(tmp_path):
    show = (
        "c = jax.config; print(c.jax_compilation_cache_dir, "
        "c.jax_persistent_cache_min_compile_time_secs, E.export_dir())"
    )
    head = "import tribojax as tj, jax, tribojax._export as E; "
    plain = f"{head}tj.FractalSurface(2.5, 1e-9, 1.0); {show}"
    opt_in = f"{head}tj.use_compilation_cache(); {show}"
    default_min = _python(f"import jax; {show.replace('E.export_dir()', '0')}", {}, tmp_path)
    default_min = default_min.stdout.split()[1]
    # without the opt-in, tribojax leaves JAX's cache settings as they were
    assert _python(plain, {}, tmp_path).stdout.split() == ["None", default_min, "None"]
    assert _python(opt_in, {"TRIBOJAX_CACHE": "off"}, tmp_path).stdout.split()[0] == "None"
    chosen = _python(opt_in, {"TRIBOJAX_CACHE_DIR": str(tmp_path / "tjc")}, tmp_path)
    assert chosen.stdout.split() == [
        str(tmp_path / "tjc" / "jax"),
        "0.0",
        str(tmp_path / "tjc" / "export"),
    ]
    users = _python(
        opt_in,
        {
            "JAX_COMPILATION_CACHE_DIR": str(tmp_path / "mine"),
            "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS": "5",
            "TRIBOJAX_CACHE_DIR": str(tmp_path / "tjc"),
        },
        tmp_path,
    )
    # the user's own JAX folder and threshold stay; tribojax's traces stay in its own folder
    assert users.stdout.split() == [str(tmp_path / "mine"), "5.0", str(tmp_path / "tjc" / "export")]
    home = _python(opt_in, {"XDG_CACHE_HOME": str(tmp_path / "xdg")}, tmp_path).stdout.split()[0]
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
        name, floor, ceiling = re.fullmatch(
            r"([A-Za-z0-9_.-]+)>=([0-9.]+)(?:,<([0-9.]+))?", spec
        ).groups()
        have = tuple(int(x) for x in re.findall(r"\d+", version(name))[:3])
        need = tuple(int(x) for x in floor.split("."))
        assert have >= need, f"{name} {version(name)} is below the floor {floor}"
        if ceiling is not None:  # an upper bound (ml_dtypes: pyproject says why)
            below = tuple(int(x) for x in ceiling.split("."))
            assert have < below, f"{name} {version(name)} is not below {ceiling}"


def _scaled(x, k, fn):  # a user's function: its source is not versioned by the key
    return fn(x) * k


def test_stored_trace_key_names_everything_the_trace_depends_on():
    import functools

    import equinox as eqx
    import jax
    import jax.numpy as jnp
    import numpy as np

    import tribojax._export as E

    def key(*args, fn=E._read):  # any tribojax function names the program (it is not traced)
        dyn, static = eqx.partition(args, eqx.is_array)
        leaves, treedef = jax.tree_util.tree_flatten(dyn)
        return E._key(fn, treedef, static, leaves)

    x = jnp.ones(3)
    base = key(x, 2.0, jnp.sin)
    assert base is not None and base == key(jnp.zeros(3), 2.0, jnp.sin)  # new data, same program
    others = [
        key(x, 3.0, jnp.sin),
        key(x, 2, jnp.sin),
        key(x, 2.0, jnp.cos),
        key(jnp.ones(4), 2.0, jnp.sin),
        key(jnp.ones(3, dtype=jnp.int32), 2.0, jnp.sin),
        key(x, 2.0, jnp.sin, fn=E._write),
    ]
    assert len({base, *others}) == 7 and None not in others
    partial = [key(x, 2.0, functools.partial(jnp.clip, min=m)) for m in (0.0, 0.5, 0.0)]
    assert partial[0] == partial[2] != partial[1] and None not in partial
    with jax.numpy_rank_promotion("allow"), jax.numpy_rank_promotion("raise"):
        assert key(x, 2.0, jnp.sin) == base
    with jax.numpy_rank_promotion("allow"):
        assert key(x, 2.0, jnp.sin) != base  # a trace-relevant setting is in the key
    # a call hashes its signature's key once; a new trace-relevant setting is a new signature
    from tribojax._model._modes import oscillator

    if E.export_dir() is not None:
        t, acc = jnp.linspace(0.0, 0.1, 50), jnp.sin(jnp.linspace(0.0, 3.0, 50))
        w, zeta = jnp.asarray([300.0]), jnp.asarray([0.05])
        q = np.asarray(oscillator(t, acc, w, zeta))
        n = len(oscillator.programs)
        # other values, same signature: no new program (the mode is linear in its drive)
        np.testing.assert_allclose(oscillator(t, 2.0 * acc, w, zeta), 2.0 * q, rtol=1e-12)
        assert len(oscillator.programs) == n
        other = "raise" if jax.config.jax_numpy_rank_promotion == "allow" else "allow"
        with jax.numpy_rank_promotion(other):
            assert np.array_equal(oscillator(t, acc, w, zeta), q)
            assert len(oscillator.programs) == n + 1
    # not keyed (traced as before): a closure, whose captured value is not in its name; a user's
    # function or Module class, whose source may change between runs without a version change
    k = 2.0
    assert key(x, 2.0, lambda v: v * k) is None
    assert key(x, 2.0, _scaled) is None and key(x, 2.0, jnp.sin, fn=_scaled) is None

    class UserModel(eqx.Module):
        w: jax.Array

    assert key(UserModel(x), 2.0, jnp.sin) is None
    fn = E.cached_jit(_scaled)  # falls back to equinox.filter_jit
    assert float(fn(x, 2.0, jnp.sin)[0]) == float(jnp.sin(1.0) * 2.0)


@pytest.mark.slow
def test_threads_meeting_new_programs_export_and_compile_one_at_a_time(tmp_path, monkeypatch):
    """Exporting, reading back and compiling a stored program build MLIR modules, which JAX does
    not support from several threads at once (jax #32354, #28551): `_export._LOWERING` makes
    threads that meet new programs take turns there, and each still gets its own numbers."""
    import threading
    import time

    import jax.numpy as jnp
    import numpy as np

    import tribojax._export as E
    from tribojax._model._modes import oscillator

    monkeypatch.setattr(E, "export_dir", lambda: tmp_path)  # new programs, in a fresh folder
    active, most = [0], [0]
    export, read = E._export, E._read

    def timed(step):
        def run(*args):
            active[0] += 1
            most[0] = max(most[0], active[0])
            time.sleep(0.2)  # a slow lowering: another thread would enter meanwhile
            try:
                return step(*args)
            finally:
                active[0] -= 1

        return run

    monkeypatch.setattr(E, "_export", timed(export))
    monkeypatch.setattr(E, "_read", timed(read))
    sizes = (3, 5, 7, 11)  # one new program per thread (the shape is in the key)
    out = {}

    def args(n):
        return (
            jnp.linspace(0.0, 0.05, n),
            jnp.linspace(1.0, -1.0, n),
            jnp.asarray([200.0]),
            jnp.asarray([0.1]),
        )

    def call(n):
        out[n] = np.asarray(oscillator(*args(n)))

    threads = [threading.Thread(target=call, args=(n,)) for n in sizes]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(out) == list(sizes) and most[0] == 1
    for n, got in out.items():  # against the plain jit, outside the threads
        np.testing.assert_allclose(got, oscillator.jitted(*args(n)), rtol=1e-12, atol=1e-300)
    assert len(list(tmp_path.glob("*.jaxexp"))) == len(sizes)  # each program stored


@pytest.mark.slow
def test_a_stored_trace_filed_under_another_key_is_traced_again_and_rewritten(
    tmp_path, monkeypatch
):
    import jax.numpy as jnp
    import numpy as np

    import tribojax._cache as C
    from tribojax._model._modes import oscillator

    monkeypatch.setattr(C, "_FOLDER", [tmp_path])  # a fresh folder of stored traces

    def args(n):
        return (
            jnp.linspace(0.0, 0.05, n),
            jnp.linspace(1.0, -1.0, n),
            jnp.asarray([200.0]),
            jnp.asarray([0.1]),
        )

    oscillator(*args(9))
    (first,) = (tmp_path / "export").glob("*.jaxexp")
    oscillator(*args(13))
    (second,) = set((tmp_path / "export").glob("*.jaxexp")) - {first}
    second.write_bytes(first.read_bytes())  # the 9-sample program filed under the 13's key
    oscillator.programs.pop(second.stem)  # as a new process meets it
    got = np.asarray(oscillator(*args(13)))
    np.testing.assert_allclose(got, oscillator.jitted(*args(13)), rtol=1e-12, atol=1e-300)
    assert second.read_bytes() != first.read_bytes()  # rewritten for its own key
    oscillator.programs.pop(second.stem)
    np.testing.assert_array_equal(oscillator(*args(13)), got)  # and read back from now on


def test_unreadable_compilation_cache_entries_are_removed(tmp_path):
    # issue 72 row 13: JAX warns on every read of a corrupted entry and never rewrites it
    from jax._src.compilation_cache import compress_executable

    from tribojax._cache import repair_compilation_cache

    good, bad = tmp_path / "jit_good-abc-cache", tmp_path / "jit_bad-def-cache"
    good.write_bytes(compress_executable(b"\0\0\0\1" + b"an executable" * 10))
    bad.write_bytes(compress_executable(b"\0\0\0\1" + b"an executable" * 10)[:-7])  # truncated
    (tmp_path / "jit_bad-def-atime").write_bytes(b"\0" * 8)
    assert repair_compilation_cache(tmp_path) == [bad]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["jit_good-abc-cache"]
    assert repair_compilation_cache(tmp_path) == []
    assert repair_compilation_cache(tmp_path / "absent") == []


def test_the_command_repairs_the_cache_once_and_says_so(capsys, monkeypatch):
    import warnings

    import tribojax._cache as cache
    from tribojax._cli import _main

    def configure():  # JAX's warnings while reading two damaged entries
        for name in ("jit_a", "jit_b"):
            warnings.warn(f"{cache.READ_ERROR} for '{name}': XlaRuntimeError: corrupted")

    monkeypatch.setattr(_main, "configure_process", configure)
    monkeypatch.setattr(cache, "repair_compilation_cache", lambda: [Path("x"), Path("y")])
    assert _main.console(["contact", "--D", "2.5", "--G", "1e-9", "--load", "5"]) == 0
    err = capsys.readouterr().err
    assert cache.READ_ERROR not in err
    assert "2 compiled programs could not be read from the cache; removed 2 unreadable" in err


@pytest.mark.slow
def test_a_corrupted_cache_is_repaired_by_the_next_run(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "EQX_ON_ERROR"}
    env["TRIBOJAX_CACHE_DIR"] = str(tmp_path / "c")
    code = "import sys; from tribojax._cli import entry; sys.argv[0] = 'tribojax'; entry()"
    cmd = [
        sys.executable,
        "-c",
        code,
        "hysteresis",
        "--n",
        "4",
        "--out",
        str(tmp_path / "h"),
        "--force",
    ]

    def run():
        out = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, out.stderr[-2000:]
        return out.stderr

    run()
    entries = sorted((tmp_path / "c" / "jax").glob("*-cache"))
    assert entries
    for e in entries:
        e.write_bytes(b"not a program" * 10)
    err = run()
    assert "Error reading" not in err and f"removed {len(entries)} unreadable entries" in err
    assert run() == ""  # stored again, read back without a word

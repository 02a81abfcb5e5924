"""A library leaves its user's process alone: a process that runs JAX, matplotlib (its own
backend) and equinox imports tribojax and computes a contact value, a slip simulation, a loop
fit and the wu2015 figure; nothing outside tribojax changes but `jax_enable_x64`. And the
settings a user made explicitly win."""

import json
import os
import subprocess
import sys

import pytest

SCENARIO = r"""
import json, os, sys
import jax
import matplotlib
matplotlib.use("svg")
import matplotlib.pyplot as plt
import equinox as eqx
import numpy as np

def equinox_functions():
    return {f"{m}.{k}": id(v) for m, mod in list(sys.modules.items())
            if m == "equinox" or m.startswith("equinox.")
            for k, v in list(vars(mod).items()) if callable(v)}

before = dict(env=dict(os.environ), config={k: repr(v) for k, v in jax.config.values.items()},
              backend=matplotlib.get_backend(), eqx=equinox_functions())
import tribojax as tj
C = tj.WANG2022_CALIBRATED
contact = tj.wang2022_table3_model(C["G_m"], C["mu_t"], C["sigma_s_Pa"], M=C["M"], D=C["D"])(5.0)
ok = [bool(np.isfinite(float(contact.K_tau)))]
if sys.argv[2] == "full":
    slip = tj.simulate_slip(tj.PreSlipLuGre(1.1, 2.0e7, 150.0, 1.0))
    loop = tj.synthetic_loop(tj.Jenkins(0.3, 10.0, 1.0e6), 6e-6, 2 * np.pi * 10.0, cycles=3,
                             samples_per_cycle=120)
    fit = tj.fit_loop(loop, "jenkins", model="steady")
    ok += [bool(slip.ok), bool(fit.converged), tj.plot_wu2015(tj.wu2015_comparison(), sys.argv[1])]
after = dict(env=dict(os.environ), config={k: repr(v) for k, v in jax.config.values.items()},
             backend=matplotlib.get_backend(), eqx=equinox_functions())
changed = {
    "env": sorted(k for k in set(before["env"]) | set(after["env"])
                  if before["env"].get(k) != after["env"].get(k)),
    "config": sorted(k for k in set(before["config"]) | set(after["config"])
                     if before["config"].get(k) != after["config"].get(k)),
    "backend": [before["backend"], after["backend"]],
    "eqx": sorted(k for k in before["eqx"] if after["eqx"].get(k) != before["eqx"][k]),
    "figures": plt.get_fignums(),
    "dir": sorted(n for n in dir(tj) if n not in tj.__all__),
    "ok": ok,
}
print(json.dumps(changed))
"""


def _run(code, tmp_path, *args, **env):
    clean = {
        k: v
        for k, v in os.environ.items()
        if k
        not in ("XLA_FLAGS", "EQX_ON_ERROR", "JAX_ENABLE_X64", "MPLBACKEND", "TRIBOJAX_CACHE_DIR")
    }
    return subprocess.run(
        [sys.executable, "-c", code, *args],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env={**clean, **env},
        timeout=600,
    )


@pytest.mark.parametrize(
    "scenario", ["contact", pytest.param("full", marks=pytest.mark.slow)]
)  # the full one: a contact value, simulate_slip, fit_loop and plot_wu2015 (20 s of compiling)
def test_import_and_use_change_nothing_outside_tribojax_but_x64(tmp_path, scenario):
    pytest.importorskip("matplotlib")
    out = _run(SCENARIO, tmp_path, str(tmp_path / "wu2015.png"), scenario)
    assert out.returncode == 0, out.stderr[-3000:]
    changed = json.loads(out.stdout.strip().splitlines()[-1])
    assert changed["ok"] == [True] * (4 if scenario == "full" else 1)
    assert changed["env"] == [] and changed["config"] == ["jax_enable_x64"], changed
    assert changed["backend"] == ["svg", "svg"] and changed["figures"] == []
    assert changed["eqx"] == [] and changed["dir"] == []
    if scenario == "full":
        assert (tmp_path / "wu2015.png").stat().st_size > 1000


def test_a_users_explicit_float32_is_refused_not_overruled(tmp_path):
    code = (
        "import os, jax, tribojax as tj\n"
        "print(os.environ['JAX_ENABLE_X64'], jax.config.jax_enable_x64)\n"
        "try:\n"
        "    tj.FractalSurface(2.5, 1e-9, 1.0)\n"
        "except RuntimeError as e:\n"
        "    print('refused:', e)\n"
    )
    out = _run(code, tmp_path, JAX_ENABLE_X64="0")
    assert out.returncode == 0, out.stderr[-3000:]
    first, second = out.stdout.strip().splitlines()[:2]
    assert first == "0 False"  # the variable and JAX's setting as the user left them
    assert second.startswith("refused: tribojax needs float64") and "JAX_ENABLE_X64" in second


def test_the_command_makes_its_process_choices_for_itself(tmp_path):
    # the console script (not the library) turns on the cache, one-kernel loops and NaN
    # failures inside equinox-based solvers for its own process; a user's EQX_ON_ERROR wins
    code = (
        "import json, os, sys\n"
        "from tribojax._cli._main import configure_process\n"
        "configure_process()\n"
        "import jax\n"
        "print(json.dumps([os.environ.get('XLA_FLAGS', ''), os.environ.get('EQX_ON_ERROR'),\n"
        "                  jax.config.jax_compilation_cache_dir]))\n"
    )
    cache = str(tmp_path / "tjc")
    flags, eqx_mode, folder = json.loads(_run(code, tmp_path, TRIBOJAX_CACHE_DIR=cache).stdout)
    assert "xla_cpu_small_while_loop_byte_threshold" in flags and eqx_mode == "nan"
    assert folder == os.path.join(cache, "jax")
    mine = _run(
        code, tmp_path, TRIBOJAX_CACHE="off", TRIBOJAX_XLA_HOIST="off", EQX_ON_ERROR="raise"
    )
    assert json.loads(mine.stdout) == ["", "raise", None]

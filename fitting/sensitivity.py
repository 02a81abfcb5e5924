"""Study: how the reticle slips and wu2015's K̄, C̄ respond to D, G, μ_t, load and acceleration.

    python -m fitting.sensitivity [--out DIR] [--short]
    XLA_FLAGS=--xla_force_host_platform_device_count=2 python -m fitting.sensitivity ...

1. Elasticities ∂ln y/∂ln p (exact, forward mode through the contact load balance and the slip
   ODE) of F_s, K_τ, C_τ, z_max and the phase slips T4–T7 (wang2022 Tables 3–7), and of
   wu2015's K̄, C̄ (Mindlin element, μN = F_s, K_d = K_τ, amplitude 50 nm), at Table 3's loads
   with the Table-3-calibrated surface (D = 2.8821, G = 4.3636e-8 m, M = 1, μ_t = 0.1416,
   σ_s = 1.893 GPa) and a_max = 1 m/s².
2. A sweep over 20 D × 20 G × 25 loads = 10⁴ surface/load combinations at contact and loop level
   (the slip ODE for 10⁴ members is left out: ~20 ms per member), vmapped and sharded across
   all JAX devices, timed against one device.

Prints the tables; with --out DIR writes DIR/sensitivity.json, DIR/elasticities.md and bar
charts / sweep maps as PNG (if matplotlib is installed). Existing files are never overwritten.
"""

import argparse
import json
import sys
import time
from pathlib import Path

import jax
import numpy as np

import tribojax as tj

TABLE3_LOADS = (3.6912, 4.9638, 6.7818, 9.5088, 12.2358, 21.3258)  # N, 0.6 ... 20 kPa (Eq 28)
TABLE3_VACUUM = (0.6, 2.0, 4.0, 7.0, 10.0, 20.0)  # kPa
CAL = tj.WANG2022_CALIBRATED  # Table 1 D and the Table 3 calibration (M = 1)
SURFACE = dict(D=CAL["D"], G=CAL["G_m"], mu_t=CAL["mu_t"], a_max=tj.WANG2022_A_MAX)
AMPLITUDE = 50e-9  # m
SWEEP_AXES = dict(
    D=np.linspace(2.70, 2.95, 20),
    G=np.geomspace(5e-9, 6e-8, 20),  # m; above ~6e-8 F_s vanishes (no elastic asperities left)
    load=np.geomspace(TABLE3_LOADS[0], TABLE3_LOADS[-1], 25),
)
OUTPUT_FILES = (
    "sensitivity.json",
    "elasticities.md",
    "elasticities_slip.png",
    "elasticities_loop.png",
    "sweep.png",
)


def elasticity_tables(loads) -> list[dict]:
    rows = []
    for vac, load in loads:
        slip = tj.slip_sensitivities(load=load, **SURFACE)
        loop = tj.hysteresis_sensitivities(load=load, A=AMPLITUDE, **SURFACE)
        rows.append({"vacuum_kPa": vac, "load_N": load, "slip": slip, "loop": loop})
    return rows


def sweep_grid() -> dict:
    return tj.product_grid(
        D=SWEEP_AXES["D"],
        G=SWEEP_AXES["G"],
        mu_t=SURFACE["mu_t"],
        load=SWEEP_AXES["load"],
        a_max=SURFACE["a_max"],
        A=AMPLITUDE,
    )


def _median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def run_sweep(repeats: int = 5) -> dict:
    chain = tj.LoopChain("mindlin")
    grid = sweep_grid()
    n = int(grid["D"].shape[0])
    devices = jax.devices()
    out = tj.sweep(chain, grid)  # compiles for every device
    single = tj.sweep(chain, grid, devices=devices[:1])
    # NumPy: the two results live on different device sets
    diff = max(float(np.max(np.abs(np.asarray(out[k]) / np.asarray(single[k]) - 1))) for k in out)
    t_all = _median_time(lambda: tj.sweep(chain, grid), repeats)
    t_one = _median_time(lambda: tj.sweep(chain, grid, devices=devices[:1]), repeats)
    values = {k: np.asarray(v) for k, v in out.items()}
    return {
        "members": n,
        "axes": {k: [float(v.min()), float(v.max()), len(v)] for k, v in SWEEP_AXES.items()},
        "fixed": {"mu_t": SURFACE["mu_t"], "a_max": SURFACE["a_max"], "A_m": AMPLITUDE},
        "devices": len(devices),
        "device_kind": devices[0].device_kind,
        "sharded_over": len(out["K_tau"].sharding.device_set),
        "max_rel_diff_sharded_vs_one_device": diff,
        "warm_median_s": {"all_devices": t_all, "one_device": t_one},
        "speedup": t_one / t_all,
        "ranges": {k: [float(v.min()), float(v.max())] for k, v in values.items()},
        "_values": values,
    }


def print_report(rows, sweep, out=sys.stdout):
    for r in rows:
        print(f"\n## {r['vacuum_kPa']:g} kPa (load {r['load_N']:g} N)", file=out)
        print("\nContact and phase slips (wang2022 Tables 3-7):\n", file=out)
        print(r["slip"].table(), file=out)
        print(f"\nwu2015 loop coefficients, Mindlin, A = {AMPLITUDE * 1e9:g} nm:\n", file=out)
        print(r["loop"].table(), file=out)
    print(
        "\ne_D is per relative change of D (+1 % of 2.8821 = +0.029); divide by D for per unit D.",
        file=out,
    )
    t = sweep["warm_median_s"]
    print(
        f"\nSweep: {sweep['members']} surface/load combinations on {sweep['devices']} device(s) "
        f"({sweep['device_kind']}), sharded over {sweep['sharded_over']}: "
        f"{t['all_devices'] * 1e3:.1f} ms warm vs {t['one_device'] * 1e3:.1f} ms on one device "
        f"(x{sweep['speedup']:.2f}); max relative difference "
        f"{sweep['max_rel_diff_sharded_vs_one_device']:.1e}",
        file=out,
    )


def plot_sweep(sweep, path) -> bool:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: sweep figure skipped")
        return False
    v = sweep["_values"]
    shape = tuple(len(SWEEP_AXES[k]) for k in ("D", "G", "load"))
    j = int(np.argmin(np.abs(SWEEP_AXES["load"] - TABLE3_LOADS[2])))  # nearest to 4 kPa
    fig, axes = plt.subplots(1, 4, figsize=(16, 3.6), constrained_layout=True)
    extent = [np.log10(SWEEP_AXES["G"][0]), np.log10(SWEEP_AXES["G"][-1])]
    extent += [SWEEP_AXES["D"][0], SWEEP_AXES["D"][-1]]
    for ax, (key, label, log) in zip(
        axes,
        [
            ("F_s", "log10 F_s / N", True),
            ("K_tau", "log10 K_τ / (N/m)", True),
            ("C_tau", "log10 C_τ / (N s/m)", True),
            ("C_bar", "C̄ (Mindlin, A = 50 nm)", False),
        ],
    ):
        z = v[key].reshape(shape)[:, :, j]
        im = ax.imshow(
            np.log10(z) if log else z, origin="lower", aspect="auto", extent=extent, cmap="viridis"
        )
        fig.colorbar(im, ax=ax, label=label)
        ax.set_xlabel("log10 G / m")
        ax.set_ylabel("D")
    fig.suptitle(f"Sweep at load {SWEEP_AXES['load'][j]:.2f} N (of {sweep['members']} members)")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="folder for JSON, markdown and PNG (files must not exist)")
    parser.add_argument("--short", action="store_true", help="4 kPa only, one timing run (CI)")
    args = parser.parse_args(argv)
    out = Path(args.out) if args.out else None
    if out is not None:
        clash = [f for f in OUTPUT_FILES if (out / f).exists()]
        if clash:
            print(
                f"refusing to overwrite {', '.join(str(out / f) for f in clash)}", file=sys.stderr
            )
            return 2
    pairs = list(zip(TABLE3_VACUUM, TABLE3_LOADS))
    loads = [pairs[2]] if args.short else pairs
    rows = elasticity_tables(loads)
    sweep = run_sweep(repeats=1 if args.short else 7)
    print_report(rows, sweep)
    if out is None:
        return 0
    out.mkdir(parents=True, exist_ok=True)
    result = {
        "study": "elasticities of the wang2022 chain and a sharded surface/load sweep",
        "surface": {**SURFACE, "M": CAL["M"], "sigma_s_Pa": CAL["sigma_s_Pa"], "gamma": 1.5},
        "loop_amplitude_m": AMPLITUDE,
        "elasticities": [
            {
                "vacuum_kPa": r["vacuum_kPa"],
                "load_N": r["load_N"],
                "slip": r["slip"].as_dict(),
                "loop": r["loop"].as_dict(),
            }
            for r in rows
        ],
        "sweep": {k: v for k, v in sweep.items() if not k.startswith("_")},
    }
    (out / "sensitivity.json").write_text(json.dumps(result, indent=2))
    with open(out / "elasticities.md", "w", encoding="utf-8") as fh:
        print_report(rows, sweep, out=fh)
    middle = rows[len(rows) // 2]
    at = f"{middle['vacuum_kPa']:g} kPa"
    middle["slip"].plot(out / "elasticities_slip.png", title=f"Contact and slip, {at}")
    middle["loop"].plot(out / "elasticities_loop.png", title=f"wu2015 loop (Mindlin), {at}")
    plot_sweep(sweep, out / "sweep.png")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

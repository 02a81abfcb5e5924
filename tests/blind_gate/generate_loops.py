"""Independent generator of synthetic friction hysteresis loops (blind test data).

Physics: a clamped dry-friction joint (sphere on flat, constant normal load N,
friction coefficient mu) is driven by a prescribed tangential displacement
u(t) = A sin(2 pi f t), t = k / (f * samples_per_cycle), k = 0 .. n-1.
The tangential force follows the Mindlin-Cattaneo partial-slip law:

* virgin curve (first loading from rest), with sliding displacement delta*:
      F = mu_N [1 - (1 - |u|/delta*)^(3/2)] sign(u)    for |u| <= delta*,
      F = +-mu_N (gross slip) beyond delta*;
* Masing's rule after each reversal at (u_r, F_r), moving in direction d = +-1:
      F = F_r + d 2 mu_N [1 - (1 - d (u - u_r)/(2 delta*))^(3/2)],
  clamped at +-mu_N (gross slip) once the branch reaches it.
The history (last reversal point, direction) is tracked sample by sample.
The measured force adds a constant offset f0 and i.i.d. Gaussian noise of sd
sigma_N drawn from numpy.random.default_rng(seed).

Output of one record NAME in DIR:
* DIR/NAME.csv  - header `time_s,displacement_m,force_N`, one row per sample ('%.17g');
* DIR/NAME.json - {"normal_load_N": mu_N / 0.3, "frequency_Hz": f,
                   "noise_std_N": sigma_N (only if state_noise), "comment": "<knobs>"}.
CLI: `python generate_loops.py --out DIR` writes a family (seeds 1..12 x
delta* in 5, 10, 20 um x sigma_N in 2, 5 N) plus DIR/manifest.json.
Only numpy and the standard library are used.
"""

import argparse
import json
import pathlib

import numpy as np

DEFAULTS = dict(
    mu_N=50.0,
    delta_star=20e-6,
    amplitude=100e-6,
    frequency=1.0,
    cycles=4,
    samples_per_cycle=2000,
    sigma_N=2.0,
    f0=0.0,
    state_noise=True,
)
ASSUMED_MU = 0.3  # normal load written to the sidecar is mu_N / ASSUMED_MU


def displacement(amplitude, frequency, cycles, samples_per_cycle):
    n = int(cycles * samples_per_cycle)
    t = np.arange(n) / (frequency * samples_per_cycle)
    return t, amplitude * np.sin(2.0 * np.pi * frequency * t)


def mindlin_masing_force(u, mu_N, delta_star):
    """Noise-free Mindlin-Cattaneo force with Masing unloading/reloading."""

    def shape(x):  # 1 - (1 - x)^(3/2), x clipped to [0, 1]
        return 1.0 - (1.0 - min(max(x, 0.0), 1.0)) ** 1.5

    force = np.zeros(len(u))
    virgin, direction, u_r, f_r = True, 0, 0.0, 0.0
    for i in range(1, len(u)):
        step = u[i] - u[i - 1]
        move = int(np.sign(step))
        if move != 0 and direction != 0 and move != direction:
            virgin, u_r, f_r = False, u[i - 1], force[i - 1]  # reversal point
        if move != 0:
            direction = move
        if virgin:
            f = np.sign(u[i]) * mu_N * shape(abs(u[i]) / delta_star)
        else:
            s = direction * (u[i] - u_r)
            f = f_r + direction * 2.0 * mu_N * shape(s / (2.0 * delta_star))
        force[i] = min(max(f, -mu_N), mu_N)
    return force


def write_record(out_dir, name, seed, **knobs):
    """Write NAME.csv and NAME.json into out_dir; return the CSV path."""
    unknown = set(knobs) - set(DEFAULTS)
    if unknown:
        raise TypeError(f"unknown knobs: {sorted(unknown)}")
    k = {**DEFAULTS, **knobs}
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t, u = displacement(k["amplitude"], k["frequency"], k["cycles"], k["samples_per_cycle"])
    clean = mindlin_masing_force(u, k["mu_N"], k["delta_star"])
    rng = np.random.default_rng(seed)
    force = clean + k["f0"] + rng.normal(0.0, k["sigma_N"], size=len(u))
    csv_path = out / f"{name}.csv"
    np.savetxt(
        csv_path,
        np.column_stack([t, u, force]),
        fmt="%.17g",
        delimiter=",",
        header="time_s,displacement_m,force_N",
        comments="",
    )
    side = {"normal_load_N": k["mu_N"] / ASSUMED_MU, "frequency_Hz": k["frequency"]}
    if k["state_noise"]:
        side["noise_std_N"] = k["sigma_N"]
    # the reader takes a free-text "comment" (the knobs; manifest.json has them as values)
    side["comment"] = json.dumps({"model": "mindlin_cattaneo_masing", "seed": seed, **k})
    (out / f"{name}.json").write_text(json.dumps(side, indent=2) + "\n")
    return csv_path


def record_name(delta_star, sigma_N, seed):
    return f"mindlin_d{round(delta_star * 1e6):02d}_s{sigma_N:g}_seed{seed:02d}"


def write_family(out_dir):
    entries = []
    for delta_star in (5e-6, 10e-6, 20e-6):
        for sigma_N in (2.0, 5.0):
            for seed in range(1, 13):
                name = record_name(delta_star, sigma_N, seed)
                knobs = {"delta_star": delta_star, "sigma_N": sigma_N}
                write_record(out_dir, name, seed, **knobs)
                entries.append({"name": name, "seed": seed, "knobs": {**DEFAULTS, **knobs}})
    manifest = pathlib.Path(out_dir) / "manifest.json"
    manifest.write_text(json.dumps({"records": entries}, indent=2) + "\n")
    return manifest


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="output directory")
    args = parser.parse_args(argv)
    manifest = write_family(args.out)
    print(f"wrote {manifest}")


if __name__ == "__main__":
    main()

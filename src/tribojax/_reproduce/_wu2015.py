"""wu2015's comparison: Jenkins and Mindlin K̄, C̄ against the paper's Eq 7, and its stiffness laws.

All K̄, C̄ are functions of Ā only, so the comparison uses a unit element (μN = 1 N, K_d = 1 N/m).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from .._checks import check_range, fail_if, finite_result
from .._contact._presets import wu2015_eq5_stiffness as wu2015_eq5_stiffness  # noqa: F401 (re-export)
from .._dynamics._harmonic import harmonic_balance
from .._export import cached_jit
from .._friction._rate_independent import Jenkins, Mindlin
from .._plot import figure, save_figure
from .._tables import data_dir, read_table

EQ7_COLUMNS = ("quantity", "A_bar_min", "A_bar_max", "slope", "intercept")
ELEMENTS = {"jenkins": Jenkins, "mindlin": Mindlin}


def wu2015_eq7() -> dict[str, np.ndarray]:
    """wu2015 Eq 7 as published: rows (quantity K|C, Ā range, slope, intercept)."""
    return read_table(
        data_dir() / "wu2015" / "eq7_fits.csv", columns=EQ7_COLUMNS, text_columns=("quantity",)
    )


def eq7_curves(A_bar, table=None):
    """(K̄_e, C̄_e) of wu2015 Eq 7 at Ā (dimensionless, 0 ≤ Ā ≤ 4.5): the published linear fits."""
    table = wu2015_eq7() if table is None else table
    A_bar = jnp.asarray(A_bar, dtype=jnp.float64)
    out = []
    for q in ("K", "C"):
        rows = [i for i, name in enumerate(table["quantity"]) if name == q]
        value = jnp.zeros_like(A_bar)
        for i in rows:
            inside = (A_bar >= table["A_bar_min"][i]) & (A_bar < table["A_bar_max"][i])
            if i == rows[-1]:
                inside = inside | (A_bar == table["A_bar_max"][i])
            value = jnp.where(inside, table["slope"][i] * A_bar + table["intercept"][i], value)
        out.append(value)
    return tuple(out)


def unit_element(name: str):
    """A `Jenkins` or `Mindlin` element with μN = 1 N and K_d = 1 N/m (A0 = 1 m), for K̄(Ā), C̄(Ā)."""
    if name not in ELEMENTS:
        raise ValueError(f"element must be one of {sorted(ELEMENTS)}, got {name!r}")
    return ELEMENTS[name](1.0, 1.0, 1.0)


@cached_jit
def _curves(element, A_bar):
    out = jax.vmap(lambda a: harmonic_balance(element, a))(A_bar)
    return out.K_bar, out.C_bar


def dimensionless_curves(name: str, A_bar):
    """K̄(Ā), C̄(Ā) (dimensionless) of the named element ("jenkins" or "mindlin"), Ā > 0."""
    A_bar = check_range(A_bar, "A_bar", 0.0)
    K, C = finite_result(
        _curves, unit_element(name), jnp.atleast_1d(A_bar), what=f"K_bar, C_bar of {name}"
    )
    return jnp.asarray(K), jnp.asarray(C)


def _cbar(element, a):
    return harmonic_balance(element, a).C_bar


@cached_jit
def _newton_peak(element, a):
    """Newton iterations on dC̄/dĀ = 0 from a (unit element: A = Ā)."""
    d1 = jax.grad(_cbar, argnums=1)
    d2 = jax.grad(d1, argnums=1)

    def step(_, x):
        return x - d1(element, x) / d2(element, x)

    a = jax.lax.fori_loop(0, 8, step, a)
    return a, _cbar(element, a)


def cbar_peak(name: str) -> tuple[float, float]:
    """(Ā, C̄) at the maximum of C̄(Ā) for the named element: a grid, then Newton on dC̄/dĀ.

    Closed forms: Jenkins Ā = 2, C̄ = 1; Mindlin Ā = 2.4, C̄ = 5/6 (docs/reproduction.md).
    """
    grid = jnp.linspace(1.05, 6.0, 100)
    _, C = dimensionless_curves(name, grid)
    a, c = finite_result(
        _newton_peak, unit_element(name), grid[int(np.argmax(C))], what=f"the C_bar peak of {name}"
    )
    return float(a), float(c)


def wu2015_comparison(n: int = 4500) -> dict:
    """Both elements against wu2015 Eq 7 on Ā ∈ [0, 4.5] (n midpoints), plus the C̄ peaks.

    Returns a JSON-ready dict: "eq7_rms" {element: {"K", "C"}} (root-mean-square of model − Eq 7
    over the midpoint grid, i.e. the continuous RMS to O(1/n²)), "cbar_peak" {element: {"Abar",
    "Cbar"}} and "curves" (Ā, Eq 7 and each model's K̄, C̄ on the grid).
    """
    A_bar = (jnp.arange(n) + 0.5) * (4.5 / n)
    K_e, C_e = eq7_curves(A_bar)
    rms, peaks, curves = {}, {}, {"A_bar": A_bar, "eq7_K": K_e, "eq7_C": C_e}
    for name in ELEMENTS:
        K, C = dimensionless_curves(name, A_bar)
        rms[name] = {
            "K": float(jnp.sqrt(jnp.mean((K - K_e) ** 2))),
            "C": float(jnp.sqrt(jnp.mean((C - C_e) ** 2))),
        }
        a, c = cbar_peak(name)
        peaks[name] = {"Abar": a, "Cbar": c}
        curves[f"{name}_K"], curves[f"{name}_C"] = K, C
    curves = {k: np.asarray(v).tolist() for k, v in curves.items()}
    return {"eq7_rms": rms, "cbar_peak": peaks, "curves": curves}


def plot_wu2015(comparison: dict, path) -> bool:
    """wu2015 Figs 18–19 and 23–24 in one: K̄ and C̄ of both models against Eq 7. PNG at `path`.

    Returns False (and writes nothing) when matplotlib is missing.
    """
    fig = figure("wu2015 figure", figsize=(10, 4), constrained_layout=True)
    if fig is None:
        return False
    c = comparison["curves"]
    axes = fig.subplots(1, 2)
    for ax, q, label in zip(axes, "KC", ("K̄ = K_eq / K_d", "C̄ = πωC_eq / K_d")):
        ax.plot(c["A_bar"], c[f"jenkins_{q}"], "C0-", label="Jenkins (macroslip, Eq 1)")
        ax.plot(c["A_bar"], c[f"mindlin_{q}"], "C3-", label="Mindlin (microslip, Eq 2)")
        ax.plot(c["A_bar"], c[f"eq7_{q}"], "k--", label="Eq 7 (fit of measurements)")
        ax.set_xlabel("Ā = A / A0")
        ax.set_ylabel(label)
        ax.set_xlim(0, 4.5)
        ax.grid(alpha=0.3)
        rms = comparison["eq7_rms"]
        ax.set_title(
            f"RMS vs Eq 7: Jenkins {rms['jenkins'][q]:.3f}, Mindlin {rms['mindlin'][q]:.3f}",
            fontsize=9,
        )
    axes[0].legend(fontsize=8)
    fig.suptitle("wu2015: dimensionless equivalent stiffness and damping (Figs 18–19, 23–24)")
    save_figure(fig, path)
    return True


def fractal_tangential_stiffness(a_l, a_c, D, E_star, nu):
    """Tangential contact stiffness K_d (N/m) of a fractal joint (wu2015 Eq 4, after Jiang 2009).

    K_d = 4(1−ν)E*D / (√(2π)(2−ν)(D−1)) · (a'_l^(D/2) a'_c^((1−D)/2) − a'_l^(1/2)): the stiffness
    of the elastic asperities, a'_c < a' ≤ a'_l, summed over the size distribution.

    Misprint corrected: the exponent of a'_c is (1 − D)/2, not the printed 1 − D/2 (the asperity
    stiffness ∝ a'^(1/2) integrated over the distribution ∝ a'^(−D/2−1); docs/reproduction.md).

    Args:
        a_l: largest truncated microcontact area a'_l, m², > 0 (from a load balance, which the
            paper does not give; e.g. `FractalContact(...)(load).a_l`).
        a_c: critical truncated area a'_c, m², 0 < a'_c ≤ a'_l (no elastic asperities otherwise).
        D: fractal dimension of the surface profile, in (1, 2) (W-M, wu2015 Eq 3; a surface
            dimension D_s in (2, 3) corresponds to D = D_s − 1).
        E_star: reduced elastic modulus, Pa, > 0.
        nu: Poisson ratio, in (−1, 0.5].
    """
    a_l = check_range(a_l, "a_l", 0.0, unit="m^2")
    a_c = check_range(a_c, "a_c", 0.0, unit="m^2")
    D = check_range(D, "D", 1.0, 2.0)
    E_star = check_range(E_star, "E_star", 0.0, unit="Pa")
    nu = check_range(nu, "nu", -1.0, 0.5, hi_open=False)
    a_c = fail_if(a_c, a_c > a_l, "a_c must not exceed a_l (wu2015 Eq 4 sums a'_c < a' <= a'_l)")
    pre = 4.0 * (1.0 - nu) * E_star * D / (math.sqrt(2.0 * math.pi) * (2.0 - nu) * (D - 1.0))
    # a_l^(D/2) a_c^((1-D)/2) - a_l^(1/2) = a_l^(1/2) [(a_l/a_c)^((D-1)/2) - 1]  (wu2015 Eq 4)
    return pre * jnp.sqrt(a_l) * jnp.expm1(0.5 * (D - 1.0) * jnp.log(a_l / a_c))

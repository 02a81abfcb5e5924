"""The papers' preset contacts and load laws: wang2022's reticle/chuck pair, equivalent surface,
Table 3 model and vacuum → load (Eq 28); wu2015's Eq 5 stiffness. The numbers live in
`tribojax._presets` (no imports there: the command line shows them without JAX)."""

from __future__ import annotations

from .._checks import check_range
from .._presets import (
    CALIBRATED_M,
    STANDARD_GRAVITY_WANG2022,
    WANG2022_GAMMA,
    WANG2022_RETICLE_MASS_KG,
    WANG2022_SUCTION_AREA_M2,
    WANG2022_TANGENTIAL_LOAD_N,
    WU2015_EQ5_COEFFICIENT,
    WU2015_EQ5_EXPONENT,
)
from .._tables import wang2022_table
from ._contact import FractalContact
from ._materials import ContactPair, Material
from ._surface import FractalSurface


def wu2015_eq5_stiffness(N):
    """K_d (N/m) from wu2015 Eq 5, K_d = 0.5924·N^0.7616, with N in newtons.

    Eq 5's units are read as N in N → K_d in N/µm, the only reading that gives the ~1e6 N/m of a
    measured loop (docs/hysteresis.md, "Measured stiffness"), so this returns 0.5924e6·N^0.7616 N/m.
    """
    N = check_range(N, "N", 0.0, unit="N")
    return WU2015_EQ5_COEFFICIENT * N**WU2015_EQ5_EXPONENT


def _wang2022_material(row: int, name: str) -> Material:
    t = wang2022_table(2)
    return Material(
        E=t["E_Pa"][row],
        nu=t["nu"][row],
        G=t["shear_modulus_Pa"][row],
        H=t["H_Pa"][row],
        sigma_y=t["yield_strength_Pa"][row],
        name=name,
    )


# wang2022 Table 2 (data/wang2022/table2_materials.csv; its columns: docs/reproduction.md)
def wang2022_chuck() -> Material:
    """Fused-quartz vacuum chuck, wang2022 Table 2: E 70.5 GPa, G 30.2 GPa, H 1.372 GPa."""
    return _wang2022_material(0, "fused quartz chuck")


def wang2022_reticle() -> Material:
    """Glass-ceramic reticle, wang2022 Table 2: E 90.3 GPa, G 36.3 GPa, H 6.5 GPa."""
    return _wang2022_material(1, "glass-ceramic reticle")


def wang2022_pair(*, sigma_s=None) -> ContactPair:
    """The reticle/chuck pair of wang2022 Table 2: E* = 41.28 GPa, G' = 9.158 GPa, H = 1.372 GPa.

    sigma_s (Pa) defaults to the softer body's tabulated yield strength, 490 MPa.
    """
    return ContactPair.from_materials(wang2022_chuck(), wang2022_reticle(), sigma_s=sigma_s)


def wang2022_surface(M, *, gamma=WANG2022_GAMMA) -> FractalSurface:
    """The equivalent surface of wang2022 Table 1 (D = 2.8821, G = 7.768e-12 m).

    M is not published; it must be given.
    """
    t = wang2022_table(1)
    row = list(t["surface"]).index("equivalent")
    return FractalSurface(D=t["D"][row], G=t["G_m"][row], M=M, gamma=gamma)


def vacuum_to_load(
    vacuum_kPa,
    *,
    suction_area_m2=WANG2022_SUCTION_AREA_M2,
    mass_kg=WANG2022_RETICLE_MASS_KG,
    g=STANDARD_GRAVITY_WANG2022,
):
    """Normal load F = A_v P_v + m g, in N (wang2022 Eq 28).

    Args:
        vacuum_kPa: vacuum degree P_v, kPa, >= 0.
        suction_area_m2: adsorption area A_v, m^2 (909 mm^2 in the paper; the nominal contact area
            of 2101.72 mm^2 is not what Table 3 uses).
        mass_kg: reticle mass, kg (0.321).
        g: gravitational acceleration, m/s^2 (9.8 reproduces Table 3).
    """
    p = check_range(vacuum_kPa, "vacuum_kPa", 0.0, lo_open=False, unit="kPa")
    return suction_area_m2 * p * 1e3 + mass_kg * g


def wang2022_table3_model(
    G,
    mu_t,
    sigma_s,
    *,
    M=CALIBRATED_M,
    D=None,
    gamma=WANG2022_GAMMA,
    tangential_load=WANG2022_TANGENTIAL_LOAD_N,
    mass=WANG2022_RETICLE_MASS_KG,
    throw=True,
) -> FractalContact:
    """The reticle/chuck contact model behind wang2022 Table 3, for given unpublished constants.

    D = 2.8821 (Table 1; pass `D` to free it) and γ = 1.5, the Table 2 pair with strength
    `sigma_s` (Pa, Eq 14), T = m·a_max = 0.321 N in T/P (Eqs 17–22), m = 0.321 kg in Eq 24,
    a = a'. G in m; `M` ridges (degenerate with G). `tangential_load` (N) and `mass` (kg) may be
    changed (the sensitivities vary a_max).
    `wang2022_table3_model(*fit.values, M=fit.fixed["M"])` rebuilds a calibration's model.
    """
    base = wang2022_pair()
    pair = ContactPair(base.E_star, base.G_star, base.H, base.nu, sigma_s)
    table1 = wang2022_surface(M, gamma=gamma)
    surface = FractalSurface(D=table1.D if D is None else D, G=G, M=M, gamma=table1.gamma)
    return FractalContact(
        surface, pair, mu_t=mu_t, tangential_load=tangential_load, mass=mass, throw=throw
    )

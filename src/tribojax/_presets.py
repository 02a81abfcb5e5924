"""The papers' constants and presets, in one place: wang2022 (reticle/chuck) and wu2015 (Eq 5).

wang2022 (docs/reproduction.md):
* Table 1: the equivalent surface, D = 2.8821, G = 7.768e-12 m (`wang2022_surface`); M is not
  published.
* Table 2: the fused-quartz chuck and the glass-ceramic reticle (`wang2022_chuck`,
  `wang2022_reticle`, `wang2022_pair`).
* Eq 28: normal load F = A_v P_v + m g with A_v = 909 mm², m = 0.321 kg, g = 9.8 m/s² (this g
  reproduces Table 3's load column; `vacuum_to_load`).
* The stage's peak acceleration a_max = 1 m/s² (`TrapezoidProfile`), so the reticle's inertial
  load in T/P (Eqs 17–22) is T = m·a_max = 0.321 N; m is also the mass of Eq 24.
* The Table 3 calibration (`calibrate_table3`, M = 1, D of Table 1): G = 4.3636e-8 m,
  μ_t = 0.1416, σ_s = 1.893 GPa, rounded to the digits printed here; tests/test_presets.py
  checks them against a fresh calibration.

wu2015: Eq 5, K_d = 0.5924·N^0.7616 (N in N, K_d in N/µm; `wu2015_eq5_stiffness`).
"""

from __future__ import annotations

from types import MappingProxyType

from ._checks import check_range
from ._contact._contact import FractalContact
from ._contact._materials import ContactPair, Material
from ._contact._surface import FractalSurface
from ._tables import wang2022_table

# --- wang2022 -----------------------------------------------------------------------------------
WANG2022_RETICLE_MASS_KG = 0.321  # m in Eqs 24 and 28
"""Mass of the reticle, kg (wang2022 Section 5): the slider mass m of Eq 24 and the m·g of Eq 28."""
WANG2022_A_MAX = 1.0  # m/s², the stage's peak acceleration
"""Peak stage acceleration a_max, m/s² (wang2022 Section 5.2, Figure 9)."""
WANG2022_TANGENTIAL_LOAD_N = WANG2022_RETICLE_MASS_KG * WANG2022_A_MAX  # T = m·a_max in T/P
"""Applied tangential load T = m·a_max = 0.321 N, N: the T of the ratio T/P in wang2022 Eqs 18–22
(the paper leaves T undefined; this reading reproduces Table 3's trend)."""
WANG2022_SUCTION_AREA_M2 = 909e-6  # A_v of Eq 28
STANDARD_GRAVITY_WANG2022 = 9.8  # m/s², g of Eq 28 (reproduces Table 3's load column)
WANG2022_GAMMA = 1.5  # YK frequency-density parameter
WANG2022_TABLE1_D = 2.8821  # Table 1, equivalent surface
# The Table 3 calibration at M = 1 and Table 1's D (tests/test_presets.py checks it).
CALIBRATED_M = 1.0
CALIBRATED_G_M = 4.3636e-8
CALIBRATED_MU_T = 0.1416
CALIBRATED_SIGMA_S = 1.893e9  # Pa
WANG2022_CALIBRATED = MappingProxyType(
    {
        "M": CALIBRATED_M,
        "D": WANG2022_TABLE1_D,
        "G_m": CALIBRATED_G_M,
        "mu_t": CALIBRATED_MU_T,
        "sigma_s_Pa": CALIBRATED_SIGMA_S,
    }
)
"""The Table 3 calibration (wang2022 Eqs 16, 19 fitted to Table 3's F_s and K_τ): M = 1, Table 1's
D = 2.8821, G_m = 4.3636e-8 m, mu_t = 0.1416, sigma_s_Pa = 1.893e9 Pa."""
# The chain fit's defaults (start and fixed values): the calibrated point and the paper's α = 1.
CHAIN_DEFAULTS = MappingProxyType(
    {
        "D": WANG2022_TABLE1_D,
        "G_m": CALIBRATED_G_M,
        "mu_t": CALIBRATED_MU_T,
        "sigma_s_Pa": CALIBRATED_SIGMA_S,
        "alpha": 1.0,
    }
)
"""Start and fixed values of the full-chain fit (`fit_measured_slips`): the Table 3 calibration
(D, G_m in m, mu_t, sigma_s_Pa in Pa) and the paper's bristle exponent alpha = 1 (wang2022
Eq 27)."""

# --- wu2015 -------------------------------------------------------------------------------------
WU2015_EQ5_COEFFICIENT = 0.5924e6  # N/m per N^exponent (Eq 5 read with K_d in N/µm)
WU2015_EQ5_EXPONENT = 0.7616  # K_d ∝ N^0.7616


def wu2015_eq5_stiffness(N):
    """K_d (N/m) from wu2015 Eq 5, K_d = 0.5924·N^0.7616, with N in newtons.

    Eq 5 is a power law (the text calls it exponential). Its units are not stated consistently:
    read literally (N in N, K_d in N/m) it gives ~1 N/m, and read in Fig 14's per-area units
    (MPa, MPa/m) a stiffness of the same absurd order for a ~1e-7 m² contact. Only the reading
    N in N → K_d in N/µm gives the ~1e6 N/m of a measured sphere-on-flat loop, so that is what is
    returned here: 0.5924e6·N^0.7616 N/m.
    """
    N = check_range(N, "N", 0.0, unit="N")
    return WU2015_EQ5_COEFFICIENT * N**WU2015_EQ5_EXPONENT


# --- wang2022 presets ---------------------------------------------------------------------------
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


# wang2022 Table 2 (bundled as data/wang2022/table2_materials.csv). The printed header is garbled;
# by the values column 1 is the fused-quartz chuck and column 2 the glass-ceramic reticle.
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


# Table 3's 4 kPa row (Eq 28): the reference load of the sensitivities, N.
WANG2022_REFERENCE_LOAD_N = WANG2022_SUCTION_AREA_M2 * 4e3 + (
    WANG2022_RETICLE_MASS_KG * STANDARD_GRAVITY_WANG2022
)


def wang2022_table3_model(G, mu_t, sigma_s, *, M=CALIBRATED_M, D=None, gamma=WANG2022_GAMMA,
                          tangential_load=WANG2022_TANGENTIAL_LOAD_N,
                          mass=WANG2022_RETICLE_MASS_KG, throw=True) -> FractalContact:  # fmt: skip
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


# The two-DOF elastic dry-friction benchmark of the harmonic-balance literature (tmdsimpy's and
# NLvib's examples; Krack & Gross 2019): DOF 0 tangential, DOF 1 normal, both against ground.
FRF_2DOF = MappingProxyType(
    {
        "M": ((1.0, 0.0), (0.0, 1.0)),  # kg
        "K": ((12.0, 0.0), (0.0, 21.0)),  # N/m
        "C_diag": (2 * 0.05 * 12**0.5, 2 * 0.1 * 100**0.5),  # N s/m, as specified (√100)
        "k_t": 5.0,  # N/m, tangential contact stiffness
        "k_n": 21.0,  # N/m, normal contact stiffness (no preload; separation when pulled)
        "mu": 0.85,
        "static": (0.0, 100.0),  # N
        "direction": (1.0, 0.1),  # first-harmonic cosine force per unit F
        "F": (0.5, 1.0, 10.0, 25.0, 50.0, 80.0, 100.0, 300.0),  # N
        "H": 8,  # harmonics 0–8
        "omega_range": (0.01, 6.0),  # rad/s
    }
)


# Units of the measured rig data (exact definitions: 1 in = 25.4 mm, 1 lbf = 4.4482216152605 N)
INCH_M = 0.0254  # m per inch
LBF_N = 4.4482216152605  # N per pound-force
KIP_N = 1000.0 * LBF_N  # N per kip (1000 lbf)
RPM_RAD_S = 2.0 * 3.141592653589793 / 60.0  # rad/s per revolution per minute
# Maxon motor of the screw-drive rig (Mablekos-Alexiou, da Cruz, Bergeles, IEEE T-RO 37(4) 2021):
# the EPOS export gives torque in % of this nominal torque (the source's sd_1dof.m, 9.84 mN m)
EPOS_NOMINAL_TORQUE_NM = 9.84e-3

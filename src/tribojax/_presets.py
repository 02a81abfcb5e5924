"""The papers' constants and presets, in one place: wang2022 (reticle/chuck) and wu2015 (Eq 5).

Each constant's source and reading (Tables 1–3, Eq 28, T = m·a_max, the Table 3 calibration) is
in docs/reproduction.md (wang2022: inputs; wang2022: Table 3 calibration).
"""

from __future__ import annotations

from types import MappingProxyType

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
# Table 3's 4 kPa row (Eq 28): the reference load of the sensitivities, N.
WANG2022_REFERENCE_LOAD_N = WANG2022_SUCTION_AREA_M2 * 4e3 + (
    WANG2022_RETICLE_MASS_KG * STANDARD_GRAVITY_WANG2022
)
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
"""The two-DOF elastic dry-friction benchmark (tmdsimpy's and NLvib's example, Krack & Gross
2019; DOF 0 tangential, DOF 1 normal, both against ground): mass, stiffness and damping matrices,
contact stiffnesses and μ, static and harmonic forcing, the forcing levels F (N), harmonics and
frequency range (`tribojax.frf_2dof_system`)."""


# Units of the measured rig data (exact definitions: 1 in = 25.4 mm, 1 lbf = 4.4482216152605 N)
INCH_M = 0.0254  # m per inch
LBF_N = 4.4482216152605  # N per pound-force
KIP_N = 1000.0 * LBF_N  # N per kip (1000 lbf)
RPM_RAD_S = 2.0 * 3.141592653589793 / 60.0  # rad/s per revolution per minute
# Maxon motor of the screw-drive rig (Mablekos-Alexiou, da Cruz, Bergeles, IEEE T-RO 37(4) 2021):
# the EPOS export gives torque in % of this nominal torque (the source's sd_1dof.m, 9.84 mN m)
EPOS_NOMINAL_TORQUE_NM = 9.84e-3

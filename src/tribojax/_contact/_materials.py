"""Materials, contact pairs and the wang2022 presets (Table 2, Eq 28)."""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_range

Scalar = Float[Array, "..."]


class Material(eqx.Module):
    """An isotropic solid.

    Fields (all array leaves, so they can be fitted or batched):
        E:       Young's modulus, Pa, > 0.
        nu:      Poisson's ratio, in (-1, 0.5).
        G:       shear modulus, Pa, > 0 (default E / (2 (1 + nu))).
        H:       hardness, Pa, > 0.
        sigma_y: yield (or shear) strength, Pa, > 0.
        name:    a label (static).
    """

    E: Scalar
    nu: Scalar
    G: Scalar
    H: Scalar
    sigma_y: Scalar
    name: str = eqx.field(static=True, default="")

    def __init__(self, E, nu, H, sigma_y, G=None, name: str = ""):
        self.E = check_range(E, "E", 0.0, unit="Pa")
        self.nu = check_range(nu, "nu", -1.0, 0.5)
        if G is None:
            G = self.E / (2.0 * (1.0 + self.nu))
        self.G = check_range(G, "G (shear modulus)", 0.0, unit="Pa")
        self.H = check_range(H, "H", 0.0, unit="Pa")
        self.sigma_y = check_range(sigma_y, "sigma_y", 0.0, unit="Pa")
        self.name = name


class ContactPair(eqx.Module):
    """Two bodies in contact, reduced to the equivalent quantities of wang2022 Sections 2–3.

    Fields:
        E_star:  equivalent modulus, Pa; 1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2 (wang2022, below Eq 4).
        G_star:  equivalent shear modulus G', Pa; 1/G' = (2 - nu1)/G1 + (2 - nu2)/G2 (below Eq 17).
        H:       hardness of the softer body, Pa.
        nu:      Poisson's ratio used in K = 0.454 + 0.41 nu (Eq 4) and in Eq 14; by default the
                 softer body's.
        sigma_s: strength in Eq 14, Pa. The paper calls it "shear strength" in the text and lists
                 a "yield strength" in Table 2; by default the softer body's sigma_y.
    """

    E_star: Scalar
    G_star: Scalar
    H: Scalar
    nu: Scalar
    sigma_s: Scalar

    def __init__(self, E_star, G_star, H, nu, sigma_s):
        self.E_star = check_range(E_star, "E_star", 0.0, unit="Pa")
        self.G_star = check_range(G_star, "G_star", 0.0, unit="Pa")
        self.H = check_range(H, "H", 0.0, unit="Pa")
        self.nu = check_range(nu, "nu", -1.0, 0.5)
        self.sigma_s = check_range(sigma_s, "sigma_s", 0.0, unit="Pa")

    @property
    def K(self):
        """Hardness coefficient K = 0.454 + 0.41 nu (wang2022, below Eq 4)."""
        return 0.454 + 0.41 * self.nu

    @classmethod
    def from_materials(cls, first: Material, second: Material, *, sigma_s=None) -> "ContactPair":
        """Combine two materials; H, nu and sigma_s come from the softer one (lower H).

        The softer body is picked with jnp.where, so this also works on traced values.
        """
        inv_e = (1 - first.nu**2) / first.E + (1 - second.nu**2) / second.E
        inv_g = (2 - first.nu) / first.G + (2 - second.nu) / second.G
        soft_first = jnp.asarray(first.H <= second.H)
        pick = lambda a, b: jnp.where(soft_first, a, b)  # noqa: E731
        return cls(
            E_star=1.0 / inv_e,
            G_star=1.0 / inv_g,
            H=pick(first.H, second.H),
            nu=pick(first.nu, second.nu),
            sigma_s=pick(first.sigma_y, second.sigma_y) if sigma_s is None else sigma_s,
        )


def _wang2022_material(row: int, name: str) -> Material:
    from .._io._tables import wang2022_table

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

    sigma_s defaults to the softer body's tabulated yield strength, 490 MPa.
    """
    return ContactPair.from_materials(wang2022_chuck(), wang2022_reticle(), sigma_s=sigma_s)


WANG2022_SUCTION_AREA_M2 = 909e-6
WANG2022_RETICLE_MASS_KG = 0.321
STANDARD_GRAVITY_WANG2022 = 9.8  # m/s^2; reproduces Table 3's load column exactly


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

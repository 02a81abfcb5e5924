"""Materials and contact pairs (the wang2022 presets are in `tribojax._presets`)."""

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
        G = self.E / (2.0 * (1.0 + self.nu)) if G is None else G
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

"""Fractal surface parameters of the Yan–Komvopoulos (YK) model (wang2022 Eq 1)."""

import equinox as eqx
from jaxtyping import Array, Float

from .._checks import check_range

Scalar = Float[Array, "..."]


class FractalSurface(eqx.Module):
    """The equivalent rough surface of a contact, in the YK parametrisation (wang2022 Eq 1).

    Fields (array leaves):
        D:     fractal dimension, in (2, 3).
        G:     fractal roughness coefficient, m, > 0.
        M:     number of superposed ridges, >= 1. wang2022 does not state the value it used.
        gamma: frequency-density parameter, > 1 (1.5 in wang2022).
    """

    D: Scalar
    G: Scalar
    M: Scalar
    gamma: Scalar

    def __init__(self, D, G, M, gamma=1.5):
        self.D = check_range(D, "D", 2.0, 3.0)
        self.G = check_range(G, "G", 0.0, unit="m")
        self.M = check_range(M, "M", 1.0, lo_open=False)
        self.gamma = check_range(gamma, "gamma", 1.0)

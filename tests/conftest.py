"""Test configuration: float64 (via the tribojax import) and strict rank promotion."""

import jax
import pytest

import tribojax as tj

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_rank_promotion", "raise")

CALIBRATED = dict(D=2.8821, G=4.3636e-8, M=1.0, mu_t=0.1416, sigma_s=1.893e9)


def make_model(D=CALIBRATED["D"], G=CALIBRATED["G"], M=1.0, mu_t=0.1416, sigma_s=1.893e9, **kw):
    """The wang2022 reticle/chuck contact with Table-3-calibrated constants (see _reproduce)."""
    pair = tj.wang2022_pair(sigma_s=sigma_s)
    kw.setdefault("tangential_load", 0.321)
    kw.setdefault("mass", 0.321)
    return tj.FractalContact(tj.FractalSurface(D=D, G=G, M=M), pair, mu_t=mu_t, **kw)


@pytest.fixture
def model():
    return make_model()


TABLE3_LOADS = (3.6912, 4.9638, 6.7818, 9.5088, 12.2358, 21.3258)

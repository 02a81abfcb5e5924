import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj


def test_wang2022_pair_equivalent_constants():
    # docs/reproduction.md: E* = 41.28 GPa, G' = 9.158 GPa, H = 1.372 GPa, K = 0.5212 (4 digits)
    pair = tj.wang2022_pair()
    assert float(pair.E_star) == pytest.approx(41.28e9, rel=2e-4)
    assert float(pair.G_star) == pytest.approx(9.158e9, rel=2e-4)
    assert float(pair.H) == 1.372e9
    assert float(pair.K) == pytest.approx(0.454 + 0.41 * 0.164, rel=1e-15)
    assert float(pair.sigma_s) == 490e6  # softer body's tabulated yield strength


def test_pair_is_symmetric_in_its_materials():
    a, b = tj.wang2022_chuck(), tj.wang2022_reticle()
    p, q = tj.ContactPair.from_materials(a, b), tj.ContactPair.from_materials(b, a)
    for name in ("E_star", "G_star", "H", "nu", "sigma_s"):
        assert float(getattr(p, name)) == pytest.approx(float(getattr(q, name)), rel=1e-14)


def test_default_shear_modulus_is_isotropic():
    m = tj.Material(E=200e9, nu=0.3, H=2e9, sigma_y=250e6)
    assert float(m.G) == pytest.approx(200e9 / 2.6, rel=1e-15)


def test_eq28_reproduces_table3_load_column():
    # g = 9.8 m/s^2 and A_v = 909 mm^2 give Table 3's loads exactly (to the 4 printed decimals)
    t3 = tj.wang2022_table(3)
    loads = np.asarray(tj.vacuum_to_load(jnp.asarray(t3["vacuum_kPa"])))
    np.testing.assert_allclose(loads, t3["load_N"], atol=5e-5)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(E=-1.0, nu=0.3, H=1e9, sigma_y=1e8), "E"),
        (dict(E=1e9, nu=0.5, H=1e9, sigma_y=1e8), "nu"),
        (dict(E=1e9, nu=-1.0, H=1e9, sigma_y=1e8), "nu"),
        (dict(E=1e9, nu=0.3, H=0.0, sigma_y=1e8), "H"),
        (dict(E=1e9, nu=0.3, H=1e9, sigma_y=-5.0), "sigma_y"),
        (dict(E=1e9, nu=0.3, H=1e9, sigma_y=1e8, G=0.0), "G"),
        (dict(E=float("nan"), nu=0.3, H=1e9, sigma_y=1e8), "E"),
    ],
)
def test_material_rejects_bad_values(kwargs, name):
    with pytest.raises(ValueError, match=rf"^{name}.* = .* outside the allowed range"):
        tj.Material(**kwargs)


def test_pair_rejects_bad_sigma_s_and_vacuum():
    with pytest.raises(ValueError, match=r"sigma_s = -1 Pa .*\(0, inf\)"):
        tj.wang2022_pair(sigma_s=-1.0)
    with pytest.raises(ValueError, match="vacuum_kPa = -2"):
        tj.vacuum_to_load(-2.0)

"""Topography reading: plain files always, instrument files through SurfaceTopography (optional)."""

import builtins
from pathlib import Path

import numpy as np
import pytest

import tribojax as tj

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "topography"


def test_two_column_profile_in_micrometres(tmp_path):
    x = np.arange(200) * 0.1
    z = np.sin(x)
    p = tmp_path / "p.txt"
    p.write_text("x_um z_um\n" + "\n".join(f"{a:.6f}\t{b:.6f}" for a, b in zip(x, z)))
    t = tj.read_topography(p, unit="um")
    assert t.is_profile and t.dx == pytest.approx(1e-7)
    np.testing.assert_allclose(t.heights, z * 1e-6, atol=1e-12)


def test_npy_map_needs_dx(tmp_path):
    p = tmp_path / "m.npy"
    np.save(p, np.ones((4, 5)))
    with pytest.raises(ValueError, match="pass dx"):
        tj.read_topography(p)
    t = tj.read_topography(p, unit="nm", dx=2.0)
    assert t.heights.shape == (4, 5) and t.dx == pytest.approx(2e-9) == t.dy


def test_malformed_files_are_refused_with_line(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text("x,z\n0,1\n1,2\n2,oops\n")
    with pytest.raises(tj.DataFileError, match="line 4"):
        tj.read_topography(p)
    p.write_text("0 1\n1 2\n2.7 3\n3 4\n")
    with pytest.raises(tj.DataFileError, match="evenly spaced"):
        tj.read_topography(p)
    with pytest.raises(tj.DataFileError, match="no such file"):
        tj.read_topography(tmp_path / "missing.csv")
    p.write_text("0 1\n")
    with pytest.raises(ValueError, match="unit"):
        tj.read_topography(p, unit="furlong")


def test_instrument_file_without_surfacetopography(tmp_path, monkeypatch):
    p = tmp_path / "scan.x3p"
    p.write_bytes(b"PK\x03\x04 not really")
    real_import = builtins.__import__

    def no_st(name, *a, **k):
        if name == "SurfaceTopography":
            raise ImportError(name)
        return real_import(name, *a, **k)

    monkeypatch.setattr(builtins, "__import__", no_st)
    with pytest.raises(ImportError, match=r"tribojax\[topography\]"):
        tj.read_topography(p)


def test_unreadable_instrument_file(tmp_path):
    pytest.importorskip("SurfaceTopography")
    p = tmp_path / "junk.x3p"
    p.write_bytes(b"\x00\x01garbage" * 10)
    with pytest.raises(tj.DataFileError, match="junk.x3p"):
        tj.read_topography(p)


# Real instrument files (../shared/data/topography): sampling as documented in its README, and
# what the estimator finds. Measured outcomes (PSD method, band chosen automatically):
#   metropro-1.dat  D ≈ 2.85, G ≈ 1.3e-10 m over 5.6-96 µm
#   di-1.di, x3p-2.x3p, xy-4.txt: no band with 2 < D < 3 (smoother than fractal: D < 2 where linear)
#   dektak-1.csv: the PSD scatters too much (single profile with spikes): no band
EXPECT = {
    "dektak-1.csv": (1.5623e-7, None),
    "xy-4.txt": (9.956e-5, None),
    "di-1.di": (9.7656e-10, None),
    "x3p-2.x3p": (1.2766e-7, None),
    "metropro-1.dat": (1.0983e-6, (2.7, 2.95)),
}


@pytest.mark.parametrize("name", sorted(EXPECT))
def test_real_files(name):
    if not SHARED.is_dir():
        pytest.skip(f"{SHARED} is absent")
    if not name.endswith(".txt"):
        pytest.importorskip("SurfaceTopography")
    topo = tj.read_topography(SHARED / name)  # xy-4.txt: unit unstated, read as m
    dx, d_range = EXPECT[name]
    assert topo.dx == pytest.approx(dx, rel=1e-3)
    if d_range is None:
        with pytest.raises(ValueError, match="no fractal scaling"):
            tj.estimate_fractal(topo, "psd")
    else:
        e = tj.estimate_fractal(topo, "psd")
        print(f"{name}: D = {e.D:.3f} ± {e.D_std:.3f}, G = {e.G:.3g} m, band {e.band} m")
        assert d_range[0] < e.D < d_range[1] and e.band[1] / e.band[0] >= 10

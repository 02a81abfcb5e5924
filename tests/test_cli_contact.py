"""`tribojax contact`: topography or D, G → contact parameters, printed and as JSON."""

import json

import jax
import numpy as np

import tribojax as tj
from tribojax._cli._main import main


def test_contact_from_D_G_matches_the_model(tmp_path, capsys):
    out = tmp_path / "c.json"
    assert (
        main(["contact", "--D", "2.8821", "--G", "4.3636e-8", "--load", "5", "--json", str(out)])
        == 0
    )
    data = json.loads(out.read_text())
    model = tj.FractalContact(
        tj.FractalSurface(2.8821, 4.3636e-8, 1.0),
        tj.wang2022_pair(sigma_s=1.893e9),
        mu_t=0.1416,
        tangential_load=0.321,
        mass=0.321,
    )
    ref = model(5.0)
    row = data["contact"][0]
    np.testing.assert_allclose(row["Fs_N"], ref.F_s, rtol=1e-12)
    np.testing.assert_allclose(row["Ktau_N_per_m"], ref.K_tau, rtol=1e-12)
    assert data["assumed"]["mu_t"] == 0.1416
    assert "assumed" in capsys.readouterr().out


def test_contact_from_topography(tmp_path, capsys):
    # A synthetic D = 2.6 profile written as CSV in µm: the pipeline recovers D and uses it.
    topo = tj.synthesize(jax.random.key(3), 2.6, 1e-9, L=1e-4, n_points=4096)
    x = np.arange(4096) * topo.dx * 1e6
    p = tmp_path / "profile.csv"
    p.write_text("x,z\n" + "\n".join(f"{a:.9g},{b:.9g}" for a, b in zip(x, topo.heights * 1e6)))
    out = tmp_path / "c.json"
    code = main(
        ["contact", "--topography", str(p), "--unit", "um", "--load", "3", "10", "--json", str(out)]
    )
    assert code == 0
    data = json.loads(out.read_text())
    assert abs(data["surface"]["D"] - 2.6) < 0.05
    assert abs(np.log10(data["surface"]["G"] / 1e-9)) < 0.3
    assert data["surface"]["method"] == "psd" and len(data["surface"]["band"]) == 2
    # more load → more static friction
    assert data["contact"][1]["Fs_N"] > data["contact"][0]["Fs_N"] > 0
    assert "band" in capsys.readouterr().out


def test_contact_bad_arguments(tmp_path, capsys):
    assert main(["contact", "--load", "5"]) == 2
    assert "tribojax contact: error: give --topography" in capsys.readouterr().err
    assert main(["contact", "--topography", str(tmp_path / "x.csv"), "--load", "5"]) == 2
    err = capsys.readouterr().err
    assert "no such file" in err and "Traceback" not in err

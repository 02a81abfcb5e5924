"""Discovery over test campaigns (issue 69, deliverable 5): which parameters moved between two
campaigns of one device. Judged on records of a NumPy stop operator written from a physical
description alone (tests/campaign_records.py, by a helper who had not seen this code)."""

import numpy as np
import pytest

import tribojax as tj
import tribojax.discovery as disc
from campaign_records import BASE, CHANGES, campaign_records

# the stop operator's property each change moves, as the Jenkins element names it
NAMES = {"F": "mu_N", "k": "K_d", "c": "f0"}
EFFECT = {
    "slip_force": "campaign_slip_force",
    "stiffness": "campaign_stiffness",
    "offset": "campaign_offset",
}


@pytest.mark.slow
@pytest.mark.parametrize("change", ["slip_force", "stiffness", "offset"])
def test_the_one_changed_property_is_named_with_both_campaigns_values(change):
    rep = disc.discover_campaigns(campaign_records(change, seed=1), "jenkins")
    assert rep.effects == (EFFECT[change],) and rep.verdict == "explained", rep.summary()
    ((prop, new),) = CHANGES[change].items()
    name, shifts = NAMES[prop], rep.shifts()
    for campaign, truth in (("A", BASE[prop]), ("B", new)):
        value, err = shifts[campaign][name]
        assert abs(value - truth) < max(4.0 * err, 2e-3 * abs(truth)), (campaign, value, err)
    held = rep.candidates[0]["heldout"]
    assert held["nrmse_after"] < 0.5 * held["nrmse_before"]
    # each campaign's view of the joint fit predicts its records to the noise (2 N of ~800 N)
    for campaign, loops in campaign_records(change, seed=1).items():
        for lp in loops:
            f = tj.predict_history(rep.final[campaign], lp)[0]
            assert np.sqrt(np.mean((f - lp.f) ** 2)) < 2.5


@pytest.mark.slow
def test_campaigns_of_one_device_unchanged_name_nothing():
    rep = disc.discover_campaigns(campaign_records("none", seed=1), "jenkins")
    assert rep.effects == () and rep.verdict == "none", rep.summary()
    assert rep.candidates[0]["delta_bic"] > -10.0
    assert rep.as_dict()["kind"] == "campaign" and rep.as_dict()["moved"] == []


def test_bad_campaign_arguments_are_refused_naming_them():
    loops = campaign_records("none", seed=2)
    with pytest.raises(ValueError, match="two or more campaigns"):
        disc.discover_campaigns({"A": loops["A"]}, "jenkins")
    with pytest.raises(ValueError, match="model must be one of"):
        disc.discover_campaigns(loops, "coulomb")
    both = loops["A"] + loops["B"]
    with pytest.raises(ValueError, match=r"per_campaign = \['F_pos'\]"):
        tj.fit_history(both, "jenkins", campaigns=["A"] * 3 + ["B"] * 3, per_campaign=["F_pos"])
    with pytest.raises(ValueError, match="one label per record"):
        tj.fit_history(both, "jenkins", campaigns=["A", "B"], per_campaign=["mu_N"])


@pytest.mark.slow
def test_discover_on_two_folders_at_one_tension_names_what_moved(tmp_path):
    import json

    from tribojax._cli._main import main

    paths = []
    for campaign, loops in campaign_records("offset", seed=3).items():
        (tmp_path / campaign).mkdir()
        for lp in loops:
            paths.append(tmp_path / campaign / f"{lp.source}.csv")
            tj.write_loop(lp, paths[-1])
    out = tmp_path / "out"
    assert main(["discover", *map(str, paths), "--model", "jenkins", "--out", str(out)]) == 0
    data = json.loads((out / "discovery.json").read_text())
    assert data["kind"] == "campaign" and data["effects"] == ["campaign_offset"]
    b_offset = data["shifts"][str(tmp_path / "B")]["f0"][0]
    assert b_offset == pytest.approx(150.0, abs=0.5)
    assert data["fitted_model"]["parameters"]["f0"] == pytest.approx(b_offset)

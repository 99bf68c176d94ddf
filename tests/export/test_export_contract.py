"""contract.json follows the env's own layouts and schemas: the observation fields in the
order, sizes and units of ObsLayout, the features of the interface's layout, the interface's
and the safety filter's parameters with their declared units, the timing of the hold."""

from __future__ import annotations

import json

import pytest

pytest.importorskip("stable_baselines3")

import export_cases as cases

from baselines.export import build, contract
from pairflock_env.safety.cbf.params import SafetyParams
from pairflock_env.task.observations import ObsLayout


def _contract(spec):
    return json.loads((cases.exported(spec) / build.CONTRACT).read_text())


@pytest.mark.parametrize("dim", [2, 3])
def test_every_built_in_observation_field_says_how_a_uav_obtains_it(dim):
    assert set(ObsLayout(dim, 4).names) <= set(contract.SOURCES)


@pytest.mark.parametrize("name", ["pair_n20_a50", "pair_quad3d"])
def test_fields_come_from_the_layouts(name):
    spec = f"sb3:{name}"
    doc, lp = _contract(spec), cases.loaded(spec)
    obs = doc["observation"]
    assert obs["size"] == lp.interface.layout.size
    assert [(f["name"], f["offset"], f["size"], f["unit"]) for f in obs["fields"]] == [
        (f.name, lp.interface.layout.slice(f.name).start, f.size, f.unit)
        for f in lp.interface.layout
    ]
    read = {f["name"] for f in obs["fields"] if f["read_by_policy"]}
    assert read == {
        "partner_offset", "partner_velocity", "target_distance", "flock_accel",
        "partner_flock_accel", "neighbor_offsets", "neighbor_velocities", "neighbor_mask",
    }  # fmt: skip
    feats = doc["interface"]["features"]["fields"]
    assert [f["name"] for f in feats] == list(lp.interface.features.names)
    assert doc["network"]["layers"][0]["inputs"] == sum(f["size"] for f in feats)
    params = {p["name"]: p for p in doc["interface"]["parameters"]}
    assert params["accel_scale"]["unit"] == "m/s^2"
    assert params["decision_period"]["value"] == lp.interface.decision_period


def test_action_frames_and_timing():
    doc = _contract("sb3:pair_quad3d")
    cfg = cases.loaded("sb3:pair_quad3d").config
    assert doc["frames"]["gravity"] == {"direction": [0.0, 0.0, -1.0], "magnitude_m_s2": 9.81}
    assert "x, y, z, w" in doc["frames"]["quaternion_order"]
    act = doc["action"]
    assert act["size"] == 3 and act["frame"] == "world frame"
    assert act["decode"]["bound_m_s2"] == min(5.0, cfg.pair_accel_limit)
    t = doc["timing"]
    assert t["decision_period_steps"] == 3 and t["policy_period_s"] == pytest.approx(0.06)
    assert doc["safety_filter"] is None
    assert doc["task"]["config"] == cfg.to_dict()


def test_the_safety_filter_a_policy_was_trained_with_is_listed():
    doc = _contract("sb3:pair_safe_a50")
    cfg = cases.loaded("sb3:pair_safe_a50").config
    sf = doc["safety_filter"]
    assert sf["name"] == "cbf" and sf["trained_with"]
    got = {p["name"]: (p["value"], p["unit"]) for p in sf["parameters"]}
    want = SafetyParams.from_config(cfg).to_dict()
    assert {k: v for k, (v, _) in got.items()} == want
    assert got["brake_accel"] == (40.0, "m/s^2") and got["sensing_radius"][1] == "m"


def test_files_are_hashed_and_no_machine_path_is_stored():
    folder = cases.exported("sb3:pair_n20_a50")
    text = (folder / build.CONTRACT).read_text()
    doc = json.loads(text)
    for name, entry in doc["files"].items():
        assert entry["bytes"] == (folder / name).stat().st_size
    assert str(folder) not in text and "/" not in doc["model"]["file"]

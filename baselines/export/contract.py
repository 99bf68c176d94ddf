"""``contract.json``: what a flight controller must feed the exported policy and what it gets.

Everything that is a list of fields comes from the objects the env itself uses: the
observation fields, their order, sizes, units and meanings from
:class:`~pairflock_env.task.observations.ObsLayout`, the network's inputs from the learning
interface's feature layout (``PairInterface.features``), the interface's parameters with
their units from its declared schema, the safety filter's parameters from
:class:`~pairflock_env.safety.cbf.params.SafetyParams`, the noise and delay the policy was
trained with from the config's sections. What this module adds per observation field is how
a UAV obtains it (:data:`SOURCES`, keyed by field name; a test checks that every built-in
field has an entry) and the frame conventions.
"""

from __future__ import annotations

from typing import Any

from baselines.export.c_interface import reads
from baselines.export.network import PolicyNetwork
from pairflock_env.config.registry import OBSERVATIONS
from pairflock_env.interfaces import PairInterface
from pairflock_env.interfaces.pair_params import PAIR_INTERFACE_SCHEMA
from pairflock_env.safety.cbf.params import SAFETY_SCHEMA, SafetyParams

__all__ = ["FORMAT", "SOURCES", "VERSION", "contract"]

FORMAT = "pairflock-policy-contract"
VERSION = 1

_REL = "world frame, relative to the observing UAV (own value subtracted)"
#: per built-in observation field: (frame, how a UAV obtains it from its state estimate and
#: what it senses or receives)
SOURCES: dict[str, tuple[str, str]] = {
    "partner_offset": (
        _REL,
        "partner's position estimate (received from the partner or from motion capture) "
        "minus the own position estimate",
    ),
    "partner_velocity": (_REL, "partner's velocity estimate minus the own velocity estimate"),
    "target_distance": ("scalar", "the pair's desired distance d_m: a constant of the mission"),
    "shared_neighbors": (
        "scalar",
        "number of UAVs within `radius` of both pair members, +2 when the members are within "
        "`radius` of each other (from both members' neighbour sets)",
    ),
    "leader_offset": (_REL, "the virtual leader's position (mission plan) minus own position"),
    "leader_velocity": (_REL, "the virtual leader's velocity minus own velocity"),
    "flock_accel": (
        "world frame",
        "own flocking command of the swarm protocol (eqs. 11-19: attraction/repulsion and "
        "velocity consensus over the UAVs within `radius`, leader pinning) for this control "
        "period, computed on board from the neighbours' and the leader's states",
    ),
    "partner_flock_accel": (
        "world frame",
        "the partner's flocking command for this control period, received from the partner "
        "(each member computes its own and sends it)",
    ),
    "neighbor_offsets": (
        _REL,
        "positions of the `obs_neighbors` nearest UAVs other than the partner, nearest first, "
        "minus own position; empty slots are 0",
    ),
    "neighbor_velocities": (_REL, "velocities of the same UAVs minus own velocity"),
    "neighbor_mask": ("scalar", "1 where the slot holds a UAV, 0 when fewer UAVs exist"),
}


def _fields(layout: Any, used: tuple[str, ...] = ()) -> list[dict[str, Any]]:
    out = []
    for f in layout:
        sl = layout.slice(f.name)
        entry = {
            "name": f.name,
            "offset": sl.start,
            "size": f.size,
            "shape": list(f.shape),
            "unit": f.unit,
            "meaning": f.description,
        }
        if used:
            frame, source = SOURCES.get(f.name) or _extra_source(f.name)
            entry |= {"frame": frame, "source": source, "read_by_policy": f.name in used}
        out.append(entry)
    return out


def _extra_source(name: str) -> tuple[str, str]:
    if name in OBSERVATIONS:
        return "see the registered field", f"registered observation field: {OBSERVATIONS[name].doc}"
    raise KeyError(f"observation field {name!r} has no source in baselines.export.contract")


def _declared(schema: Any, values: dict[str, Any]) -> list[dict[str, Any]]:
    return [
        {"name": n, "value": v, "unit": schema.fields[n].unit, "meaning": schema.fields[n].doc}
        for n, v in values.items()
        if n in schema.fields
    ]


def _section(cfg: Any, name: str) -> list[dict[str, Any]]:
    fields = cfg.schema.section(name).fields
    return _declared(cfg.schema, {f.name: getattr(cfg, f.name) for f in fields})


def _frames(cfg: Any) -> dict[str, Any]:
    axes = "x, y (the plane of flight)" if cfg.dim == 2 else "x, y, z, right-handed, z up"
    return {
        "world_axes": axes,
        "origin": "any fixed point: the policy reads only differences of positions",
        "gravity": (
            "none in a 2-D task"
            if cfg.dim == 2
            else {"direction": [0.0, 0.0, -1.0], "magnitude_m_s2": cfg.quad_gravity}
        ),
        "accelerations": "kinematic (gravity excluded): the vehicle's controller adds the "
        "thrust that carries the weight",
        "quaternion_order": "none observed or commanded; rotate body-frame estimates into the "
        "world frame first. The Crazyflie firmware's struct quat and this project's Crazyflie "
        "model (quat_xyzw) use x, y, z, w (scalar last); MuJoCo uses w, x, y, z",
    }


_C_API = {
    "pairflock_policy(const float *observation, float *action)": "the physical observation "
    "(the fields above, in order) -> the action below: encode, network and decode, a decision "
    "every call (what the sb3: policy returns without a state)",
    "pairflock_policy_encode(const float *observation, float *features)": "the interface's "
    "encode: observation -> the network's input",
    "pairflock_policy_network(const float *features, float *net_action)": "the network: what "
    "SB3's predict(features, deterministic=True) and policy.onnx return",
    "pairflock_policy_decode(const float *observation, const float *net_action, float *action)": (
        "the interface's decode of a (held) network output against the fresh observation"
    ),
}


def _action(net: PolicyNetwork, interface: Any) -> dict[str, Any]:
    cfg = interface.config
    L = cfg.pair_accel_limit
    out: dict[str, Any] = {
        "size": net.output_size,
        "dtype": "float32",
        "unit": f"pair_accel_limit = {L:g} m/s^2 per unit",
        "frame": "world frame",
        "meaning": "the UAV's pair acceleration u / pair_accel_limit",
        "applied": "a_des = flock_accel + pair_accel_limit * clip(action, -1, 1) (after the "
        "safety filter when one is listed below), held for one control period; the vehicle "
        "tracks a_des (on a Crazyflie: as a cmdFullState setpoint, docs/crazyflie.md)",
    }
    if isinstance(interface, PairInterface):
        p = interface.params
        out["decode"] = {
            "formula": "a = clip(net_action, -1, 1); u = accel_scale R^T a"
            + (" + (partner_flock_accel - flock_accel) / 2" if p.feedforward else "")
            + "; u *= min(1, bound / |u|); action = u / pair_accel_limit",
            "pair_frame": "R rows e_r = partner_offset / |partner_offset|, e_t = e_r turned by "
            "+90 deg (3-D: e_t1 = up x e_r normalised, e_t2 = e_r x e_t1)",
            "accel_scale_m_s2": p.accel_scale,
            "max_accel_m_s2": p.max_accel,
            "bound_m_s2": min(p.max_accel, L),
            "feedforward": p.feedforward,
        }
    else:
        out["decode"] = {"formula": "action = net_action (the world interface)"}
    return out


def _safety(cfg: Any) -> dict[str, Any] | None:
    if cfg.safety_filter == "none":
        return None
    params = SafetyParams.from_config(cfg)
    return {
        "name": cfg.safety_filter,
        "trained_with": True,
        "exported": "no: the C holds the policy only; run the filter with these parameters "
        "between the decoded command and the vehicle, as the env did in training",
        "applies_to": "the decoded pair command u = pair_accel_limit * action (m/s^2), before "
        "a_des = flock_accel + u; each paired UAV filters its own from what it senses "
        "(docs/safety.md)",
        "parameters": _declared(SAFETY_SCHEMA, params.to_dict()),
    }


def contract(
    net: PolicyNetwork, interface: Any, model: dict[str, Any], files: dict[str, Any]
) -> dict[str, Any]:
    """The contract of an export: ``model`` describes the source model (name, sha256,
    algorithm), ``files`` the written files."""
    cfg = interface.config
    used = reads(interface)
    features = {"size": interface.observation_size, "dtype": "float32"}
    if isinstance(interface, PairInterface):
        features |= {"bound": interface.observation_bound, "fields": _fields(interface.features)}
        params = _declared(PAIR_INTERFACE_SCHEMA, interface.params.to_dict())
    else:
        features |= {"fields": "the physical observation, clipped to its box"}
        params = [{"name": "decision_period", "value": interface.decision_period}]
    period = cfg.dt * interface.decision_period
    return {
        "format": FORMAT,
        "version": VERSION,
        "model": model,
        "files": files,
        "frames": _frames(cfg),
        "observation": {
            "size": interface.layout.size,
            "dtype": "float32",
            "fields": _fields(interface.layout, used),
        },
        "interface": {"name": interface.name, "parameters": params, "features": features},
        "network": net.describe(),
        "c_api": _C_API,
        "action": _action(net, interface),
        "timing": {
            "control_dt_s": cfg.dt,
            "decision_period_steps": interface.decision_period,
            "policy_period_s": period,
            "policy_rate_hz": 1.0 / period,
            "hold": "run encode + network at an episode's first step and then every "
            "decision_period control steps; decode the held network output against the "
            "fresh observation every control step",
        },
        "safety_filter": _safety(cfg),
        "robustness": _section(cfg, "robustness"),
        "task": {"dynamics": cfg.dynamics, "config": cfg.to_dict()},
    }

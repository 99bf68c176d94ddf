"""Frozen, validated configuration for a pair-flocking swarm, and the named presets.

Every quantity is in SI units (m, s, m/s, m/s^2). Equation numbers refer to Liu et al.,
"Pairwise Control in Unmanned Aerial Vehicle Swarm Flocking" (see ``docs/paper-notes.md``
for the errata this project follows).

A configuration is one flat frozen dataclass, :class:`PairFlockConfig`, so that every view
(PettingZoo, Gymnasium, SB3) accepts the same keyword overrides::

    cfg = make_config("paper", n_uavs=100, d_m=4.0)

Unknown keywords, wrong types and out-of-range values raise ``ValueError``/``TypeError``
naming the field, the value and what is valid.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = [
    "PRESETS",
    "PairFlockConfig",
    "make_config",
    "preset_names",
]

_DYNAMICS = ("particle", "quadrotor")
_INTEGRATORS = ("semi_implicit", "exact")
_INITS = ("corners", "random")
_LEADERS = ("constant_velocity", "climb_and_turn")
_QUAD_MIXERS = ("desaturate", "clip")
#: vector fields given as one repeated number are re-broadcast when ``replace`` changes dim
_BROADCAST_VECTORS = ("leader_position", "leader_velocity", "swarm_center")


def _bad(field: str, value: Any, valid: str, exc: type[Exception] = ValueError) -> Exception:
    return exc(f"{field}={value!r} is invalid: {valid}")


@dataclasses.dataclass(frozen=True)
class PairFlockConfig:
    """All parameters of one pair-flocking task (swarm, flocking law, pairs, episode, reward).

    Vector-valued fields (``leader_position``, ``leader_velocity``) accept a scalar, which is
    broadcast to every axis, or a sequence of length ``dim``.
    """

    preset: str | None = None
    """Name of the preset this config was built from (informational; baselines take their
    default gains from it). ``make_config`` fills it in."""

    # --- swarm and vehicle ---------------------------------------------------------------
    n_uavs: int = 50
    """Number of UAVs N in each swarm (>= 2)."""
    dim: int = 2
    """Spatial dimension (2 or 3; the quadrotor needs 3)."""
    dynamics: str = "particle"
    """Vehicle model: ``"particle"`` (double integrator, eq. 1) or ``"quadrotor"`` (6-DOF rigid
    body behind a geometric attitude controller, ``quad_*`` fields; needs dim=3)."""

    # --- timing --------------------------------------------------------------------------
    dt: float = 0.01
    """Control period in s: the protocol and the pair action are held over it (zero-order hold)."""
    substeps: int = 1
    """Physics substeps per control period (physics step = dt / substeps)."""
    integrator: str = "semi_implicit"
    """Particle integrator: ``"semi_implicit"`` (symplectic Euler, the paper's) or ``"exact"``
    (exact solution of the double integrator under a held acceleration)."""
    horizon: float = 50.0
    """Episode length in s (truncation); ignored when ``max_cycles`` is set."""
    max_cycles: int | None = None
    """Episode length in control steps; overrides ``horizon`` when given."""

    # --- flocking protocol, eqs. 11-19 ---------------------------------------------------
    spacing: float = 7.0
    """Desired inter-UAV distance d of eq. 4 (m); attraction and repulsion balance here."""
    radius: float = 8.4
    """Perception radius r of eq. 2 (m): UAVs farther apart than r do not interact."""
    attraction: float = 1.0
    """Slope a of the linear attraction g_a (1/s^2)."""
    repulsion: float = 10.0
    """Peak b_r of the bounded repulsion g_r(rho) = b_r exp(-rho^2/sigma^2) (1/s^2); sigma is
    set by g_r(spacing) = attraction, so ``repulsion`` must exceed ``attraction``."""
    consensus: float = 1.0
    """Velocity-consensus weight b of eq. 18 (1/s)."""
    pinning: Any = "all"
    """Pinned UAVs h_i of eq. 6: ``"all"``, an int k (the k UAVs nearest to the leader at
    reset) or a tuple of UAV indices."""
    pin_position_gain: float = 0.1
    """c1 of eq. 19 (1/s^2)."""
    pin_velocity_gain: float = 0.632
    """c2 of eq. 19 (1/s)."""

    # --- virtual leader ------------------------------------------------------------------
    leader: str = "constant_velocity"
    """Leader trajectory: ``"constant_velocity"`` or ``"climb_and_turn"`` (Sec. VI-B: climb,
    level off, smooth heading turns; see ``pairflock_env.leader.ClimbAndTurnLeader``)."""
    leader_position: Any = 25.0
    """Leader position at t = 0 (m)."""
    leader_velocity: Any = 0.5
    """Leader velocity at t = 0 (m/s). ``"climb_and_turn"``: its horizontal part sets the
    ground speed and initial heading, its vertical part (3-D) the climb rate."""
    leader_climb_time: float | None = None
    """``"climb_and_turn"``: the climb (vertical velocity) lasts this long (s); None = forever."""
    leader_level_time: float = 0.0
    """``"climb_and_turn"``: after the climb, the vertical velocity fades to 0 over this many
    seconds along a half-cosine (0 = levels off at once)."""
    leader_turns: Any = ()
    """``"climb_and_turn"``: heading turns ((start s, duration s, angle deg), ...), in time
    order and not overlapping; positive angles turn left (counter-clockwise seen from above).
    The heading follows psi0 + angle (1 - cos(pi (t - start) / duration)) / 2 in a turn."""

    # --- pairs ---------------------------------------------------------------------------
    pairs: Any = ((0, 1),)
    """Disjoint pairs (A, B) of UAV indices; y = q_B - q_A (eq. 21)."""
    d_m: Any = 5.0
    """Desired pair distance d_m (m): one value for every pair or one per pair."""
    surface_slope: float = 4.0
    """Slope c of the sliding surface s = c e + e' (eq. 26, 1/s) used in infos and metrics;
    the sliding-mode baseline uses the same value unless told otherwise."""
    pair_accel_limit: float = 1000.0
    """Bound on each component of a pair action, in m/s^2 (action 1.0 = this acceleration)."""

    # --- initial state -------------------------------------------------------------------
    init: str = "corners"
    """``"corners"``: pair members in opposite corners (the paper's extreme case);
    ``"random"``: pair members anywhere in the corner box."""
    swarm_half_width: Any = 50.0
    """Unpaired UAVs start uniform in [-w, w]^dim around ``swarm_center`` (m), at rest; one
    number for every axis or one per axis."""
    pair_corner: Any = 90.0
    """Pair members start at ``swarm_center`` -/+ this offset on every axis (m)
    (``init="corners"``); one number for every axis or one per axis (>= 0, not all 0)."""
    swarm_center: Any = 0.0
    """Centre of the start box (m); a number for every axis or a sequence of ``dim``."""
    min_init_spacing: float = 2.0
    """No two UAVs start closer than this (m)."""

    # --- reward and safety ---------------------------------------------------------------
    reward_error_weight: float = 1.0
    """Weight of |pair error| (per m) in the per-agent penalty."""
    reward_effort_weight: float = 0.01
    """Weight of (||u|| / pair_accel_limit)^2."""
    reward_separation_weight: float = 1.0
    """Weight of max(0, safe_distance - min_separation) / safe_distance."""
    reward_collision_weight: float = 10.0
    """Penalty per step while min_separation < collision_distance."""
    safe_distance: float = 1.0
    """Separation (m) below which the separation penalty starts."""
    collision_distance: float = 0.5
    """Two UAVs closer than this (m) count as a collision."""
    terminate_on_collision: bool = False
    """End the episode (terminated) when a paired UAV collides."""
    divergence_limit: float = 1e6
    """A swarm whose |position| or |velocity| exceeds this, or turns non-finite, is flagged
    ``diverged`` and its episode ends."""

    # --- observation ---------------------------------------------------------------------
    obs_neighbors: int = 6
    """Number K of nearest non-partner UAVs in each agent's observation."""

    # --- robustness (what the paper's proofs assume away) ---------------------------------
    obs_noise_position: float = 0.0
    """Std (m) of white Gaussian noise on the observed partner offset y, per axis and step."""
    obs_noise_velocity: float = 0.0
    """Std (m/s) of white Gaussian noise on the observed relative velocity y'."""
    partner_delay: int = 0
    """Communication delay, in control steps, of the partner's state (position, velocity,
    flocking command) as each agent sees it."""
    disturbance_std: float = 0.0
    """Std (m/s^2) of a random acceleration added to every UAV's command, per axis, drawn
    each control period and held over it."""

    # --- quadrotor (dynamics="quadrotor"; docs/quadrotor.md) ------------------------------
    # Airframe: the paper's mass and inertia (Sec. VI-B); the rest from an F450-class frame as
    # identified by T. Luukkonen, "Modelling and control of quadcopter", Aalto University
    # (2011), Table 1 (m = 0.468 kg, close to the paper's 0.455 kg).
    quad_mass: float = 0.455
    """Mass m (kg). Source: the paper, Sec. VI-B."""
    quad_inertia: Any = (0.43e-2, 0.43e-2, 1.02e-2)
    """Principal moments of inertia (Jxx, Jyy, Jzz) (kg m^2), body axes. Source: the paper,
    Sec. VI-B. (Jzz > Jxx + Jyy, which no rigid body has exactly; used as given.)"""
    quad_arm_length: float = 0.225
    """Distance from the centre of mass to each rotor axis, L (m). Source: Luukkonen (2011)."""
    quad_thrust_coeff: float = 2.98e-6
    """Rotor thrust coefficient k_f, T = k_f W^2 (N s^2/rad^2). Source: Luukkonen (2011)."""
    quad_torque_coeff: float = 1.14e-7
    """Rotor drag-torque coefficient k_m, reaction torque k_m W^2 (N m s^2/rad^2). Source:
    Luukkonen (2011)."""
    quad_motor_thrust_min: float = 0.05
    """Smallest thrust of one rotor (N): motors idle, they do not stop or reverse (rotor
    speed sqrt(0.05 / k_f) = 130 rad/s). Assumed idle level, as in docs/quadrotor.md."""
    quad_motor_thrust_max: float = 2.79
    """Largest thrust of one rotor (N): 4 x 2.79 N = 2.5 x the weight of 0.455 kg, a common
    thrust-to-weight design margin for small multirotors (rotor speed 968 rad/s). Assumed,
    as in docs/quadrotor.md."""
    quad_mixer: str = "desaturate"
    """What the mixer does when a rotor would leave its thrust range: ``"desaturate"`` (keep
    the direction of the body moments and give up collective thrust first, as flight stacks
    do) or ``"clip"`` (clip each rotor on its own, which distorts the moments)."""
    quad_motor_time_constant: float = 0.03
    """Time constant tau of the first-order rotor-speed response (s); 0 = instantaneous.
    Assumed, in the tens-of-milliseconds range identified for brushless motors of this size
    (e.g. Eschmann et al. 2024, arXiv:2404.07837)."""
    quad_drag: float = 0.0
    """Linear translational drag coefficient k_d, force -k_d p (kg/s); the controller
    compensates it. 0 (the paper's rigid-body model); Luukkonen (2011) identifies 0.25."""
    quad_gravity: float = 9.81
    """Gravitational acceleration g (m/s^2)."""
    quad_attitude_freq: float = 15.0
    """Roll/pitch natural frequency wn of the attitude loop (rad/s): K_R = J wn^2."""
    quad_attitude_damping: float = 0.9
    """Damping ratio zeta of the attitude loop (all axes): K_w = 2 zeta J wn."""
    quad_yaw_freq: float = 5.0
    """Yaw natural frequency of the attitude loop (rad/s)."""
    quad_accel_limit: float = 6.0
    """Largest norm of the desired acceleration the vehicle accepts (m/s^2); larger
    commands are scaled down (reported as ``accel_limited``)."""
    quad_tilt_limit: float = 35.0
    """Tilt cone (deg): the desired thrust direction stays within this angle of vertical
    (horizontal command scaled down, reported as ``accel_limited``). In (0, 90)."""
    quad_yaw: float = 0.0
    """Fixed heading psi of every quadrotor (deg, from the world x axis)."""
    quad_crash_tilt: float = 90.0
    """A UAV tilted beyond this (deg) has flipped: it crashes (episode ends). In
    (quad_tilt_limit, 180]; 180 disables the check."""
    quad_ground_altitude: float | None = None
    """A UAV below this altitude z (m) has hit the ground and crashes; None = no ground."""

    # ------------------------------------------------------------------------------------
    def __post_init__(self) -> None:
        _validate(self)

    # Derived, read-only quantities ------------------------------------------------------
    @property
    def n_pairs(self) -> int:
        return len(self.pairs)

    @property
    def n_agents(self) -> int:
        """Number of paired UAVs (the PettingZoo agents)."""
        return 2 * len(self.pairs)

    @property
    def episode_steps(self) -> int:
        """Control steps per episode (``max_cycles`` or ``round(horizon / dt)``)."""
        if self.max_cycles is not None:
            return int(self.max_cycles)
        return max(1, round(self.horizon / self.dt))

    @property
    def physics_dt(self) -> float:
        return self.dt / self.substeps

    @property
    def repulsion_sigma2(self) -> float:
        """sigma^2 of the repulsion, chosen so that g_r(spacing) = attraction."""
        return self.spacing**2 / math.log(self.repulsion / self.attraction)

    @property
    def d_m_array(self) -> np.ndarray:
        """d_m per pair, shape (n_pairs,)."""
        return np.asarray(self.d_m, dtype=np.float64)

    def vector(self, name: str) -> np.ndarray:
        """A vector field broadcast to shape (dim,)."""
        return np.asarray(getattr(self, name), dtype=np.float64)

    def replace(self, **overrides: Any) -> PairFlockConfig:
        """A copy with some fields changed (validated; unknown names raise ``ValueError``)."""
        _check_names(overrides)
        merged = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        merged.update(overrides)
        # Scalars that were broadcast for the old dim are re-broadcast for a new one.
        if "dim" in overrides:
            for name in _BROADCAST_VECTORS:
                if name not in overrides:
                    v = np.asarray(merged[name])
                    if v.ndim == 1 and np.all(v == v[0]):
                        merged[name] = float(v[0])
        if "pairs" in overrides and "d_m" not in overrides:
            d = np.asarray(merged["d_m"])
            if d.ndim == 1 and np.all(d == d[0]):
                merged["d_m"] = float(d[0])
        return PairFlockConfig(**merged)

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python dict (JSON/YAML friendly) of every field."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if isinstance(v, tuple):
                v = [list(x) if isinstance(x, tuple) else x for x in v]
            out[f.name] = v
        return out


# ---------------------------------------------------------------------------------------
# validation
# ---------------------------------------------------------------------------------------
_FIELD_NAMES = None


def field_names() -> tuple[str, ...]:
    global _FIELD_NAMES
    if _FIELD_NAMES is None:
        _FIELD_NAMES = tuple(f.name for f in dataclasses.fields(PairFlockConfig))
    return _FIELD_NAMES


def _check_names(overrides: Mapping[str, Any]) -> None:
    names = field_names()
    for key in overrides:
        if key not in names:
            hint = difflib.get_close_matches(key, names, n=3)
            extra = f" Did you mean {', '.join(map(repr, hint))}?" if hint else ""
            raise ValueError(
                f"unknown configuration field {key!r}.{extra} Valid fields: {', '.join(names)}."
            )


def _set(cfg: PairFlockConfig, name: str, value: Any) -> None:
    object.__setattr__(cfg, name, value)


def _as_int(name: str, value: Any, lo: int | None = None, hi: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise _bad(name, value, "must be an integer", TypeError)
    value = int(value)
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        rng = f">= {lo}" if hi is None else f"in [{lo}, {hi}]"
        raise _bad(name, value, f"must be an integer {rng}")
    return value


def _as_float(name: str, value: Any, *, positive: bool = False, nonneg: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise _bad(name, value, "must be a real number", TypeError)
    value = float(value)
    if not math.isfinite(value):
        raise _bad(name, value, "must be finite")
    if positive and value <= 0:
        raise _bad(name, value, "must be > 0")
    if nonneg and value < 0:
        raise _bad(name, value, "must be >= 0")
    return value


def _as_box(name: str, value: Any, dim: int) -> float | tuple[float, ...]:
    """A half-width: one number >= 0 (kept as a float) or ``dim`` numbers >= 0, not all 0."""
    if np.ndim(value) == 0:
        return _as_float(name, value, positive=True)
    v = _as_vector(name, value, dim)
    if min(v) < 0 or max(v) <= 0:
        raise _bad(name, value, "components must be >= 0 and not all 0")
    return v


def _as_choice(name: str, value: Any, choices: Sequence[str]) -> str:
    if value not in choices:
        raise _bad(name, value, f"must be one of {', '.join(map(repr, choices))}")
    return value


def _as_vector(name: str, value: Any, dim: int) -> tuple[float, ...]:
    arr = np.asarray(value, dtype=object)
    if arr.ndim == 0:
        v = _as_float(name, value)
        return (v,) * dim
    if arr.ndim != 1 or len(arr) != dim:
        raise _bad(name, value, f"must be a number or a sequence of {dim} numbers (dim={dim})")
    return tuple(_as_float(name, x) for x in arr)


def _validate(cfg: PairFlockConfig) -> None:
    if cfg.preset is not None and not isinstance(cfg.preset, str):
        raise _bad("preset", cfg.preset, "must be a preset name or None", TypeError)
    _set(cfg, "n_uavs", _as_int("n_uavs", cfg.n_uavs, 2))
    _set(cfg, "dim", _as_int("dim", cfg.dim, 2, 3))
    _set(cfg, "dynamics", _as_choice("dynamics", cfg.dynamics, _DYNAMICS))
    if cfg.dynamics == "quadrotor" and cfg.dim != 3:
        raise _bad("dim", cfg.dim, 'must be 3 with dynamics="quadrotor"')
    _set(cfg, "dt", _as_float("dt", cfg.dt, positive=True))
    _set(cfg, "substeps", _as_int("substeps", cfg.substeps, 1))
    _set(cfg, "integrator", _as_choice("integrator", cfg.integrator, _INTEGRATORS))
    _set(cfg, "horizon", _as_float("horizon", cfg.horizon, positive=True))
    if cfg.max_cycles is not None:
        _set(cfg, "max_cycles", _as_int("max_cycles", cfg.max_cycles, 1))

    for name in ("spacing", "radius", "attraction", "repulsion"):
        _set(cfg, name, _as_float(name, getattr(cfg, name), positive=True))
    if cfg.radius <= cfg.spacing:
        raise _bad("radius", cfg.radius, f"must exceed spacing={cfg.spacing} (eq. 4: d < r)")
    if cfg.repulsion <= cfg.attraction:
        raise _bad(
            "repulsion",
            cfg.repulsion,
            f"must exceed attraction={cfg.attraction} so that g_r(spacing) = attraction",
        )
    for name in ("consensus", "pin_position_gain", "pin_velocity_gain"):
        _set(cfg, name, _as_float(name, getattr(cfg, name), nonneg=True))

    n = cfg.n_uavs
    pin = cfg.pinning
    if isinstance(pin, str):
        _as_choice("pinning", pin, ("all",))
    elif isinstance(pin, (int, np.integer)) and not isinstance(pin, bool):
        _set(cfg, "pinning", _as_int("pinning", pin, 0, n))
    elif isinstance(pin, Sequence) and not isinstance(pin, str):
        idx = []
        for x in pin:
            if isinstance(x, bool) or not isinstance(x, (int, np.integer)) or not 0 <= x < n:
                raise _bad("pinning", pin, f"indices must be integers in [0, {n - 1}]")
            idx.append(int(x))
        if len(set(idx)) != len(idx):
            raise _bad("pinning", pin, "indices must be distinct")
        _set(cfg, "pinning", tuple(sorted(idx)))
    else:
        raise _bad("pinning", pin, '"all", an int k or a sequence of UAV indices', TypeError)

    _set(cfg, "leader", _as_choice("leader", cfg.leader, _LEADERS))
    _set(cfg, "leader_position", _as_vector("leader_position", cfg.leader_position, cfg.dim))
    _set(cfg, "leader_velocity", _as_vector("leader_velocity", cfg.leader_velocity, cfg.dim))
    _validate_leader_path(cfg)

    pairs = cfg.pairs
    if not isinstance(pairs, Sequence) or isinstance(pairs, str) or len(pairs) == 0:
        raise _bad("pairs", pairs, "must be a non-empty sequence of (A, B) index pairs")
    norm = []
    seen: set[int] = set()
    for pr in pairs:
        if (
            not isinstance(pr, Sequence)
            or isinstance(pr, str)
            or len(pr) != 2
            or any(isinstance(x, bool) or not isinstance(x, (int, np.integer)) for x in pr)
        ):
            raise _bad("pairs", pairs, "each pair must be two integer UAV indices (A, B)")
        a, b = int(pr[0]), int(pr[1])
        for x in (a, b):
            if not 0 <= x < n:
                raise _bad("pairs", pairs, f"indices must be in [0, {n - 1}] (n_uavs={n})")
        if a == b or a in seen or b in seen:
            raise _bad("pairs", pairs, "pairs must be disjoint: no UAV may appear twice")
        seen.update((a, b))
        norm.append((a, b))
    _set(cfg, "pairs", tuple(norm))

    dm = cfg.d_m
    if np.ndim(dm) == 0:
        dm_t = (_as_float("d_m", dm, positive=True),) * len(norm)
    else:
        if len(dm) != len(norm):
            raise _bad("d_m", dm, f"must be one number or {len(norm)} numbers (one per pair)")
        dm_t = tuple(_as_float("d_m", x, positive=True) for x in dm)
    _set(cfg, "d_m", dm_t)
    _set(cfg, "surface_slope", _as_float("surface_slope", cfg.surface_slope, positive=True))
    _set(
        cfg,
        "pair_accel_limit",
        _as_float("pair_accel_limit", cfg.pair_accel_limit, positive=True),
    )

    _set(cfg, "init", _as_choice("init", cfg.init, _INITS))
    for name in ("swarm_half_width", "pair_corner"):
        _set(cfg, name, _as_box(name, getattr(cfg, name), cfg.dim))
    _set(cfg, "swarm_center", _as_vector("swarm_center", cfg.swarm_center, cfg.dim))
    _set(cfg, "min_init_spacing", _as_float("min_init_spacing", cfg.min_init_spacing, nonneg=True))
    if cfg.init == "corners" and len(norm) > 2 ** (cfg.dim - 1):
        raise _bad(
            "init",
            cfg.init,
            f'"corners" places at most {2 ** (cfg.dim - 1)} pairs in {cfg.dim}-D '
            f'(one per diagonal): with {len(norm)} pairs init must be "random"',
        )

    for name in (
        "reward_error_weight",
        "reward_effort_weight",
        "reward_separation_weight",
        "reward_collision_weight",
    ):
        _set(cfg, name, _as_float(name, getattr(cfg, name), nonneg=True))
    _set(cfg, "safe_distance", _as_float("safe_distance", cfg.safe_distance, positive=True))
    _set(
        cfg,
        "collision_distance",
        _as_float("collision_distance", cfg.collision_distance, nonneg=True),
    )
    if not isinstance(cfg.terminate_on_collision, (bool, np.bool_)):
        raise _bad(
            "terminate_on_collision", cfg.terminate_on_collision, "must be a bool", TypeError
        )
    _set(
        cfg,
        "divergence_limit",
        _as_float("divergence_limit", cfg.divergence_limit, positive=True),
    )
    _set(cfg, "obs_neighbors", _as_int("obs_neighbors", cfg.obs_neighbors, 0))
    for name in ("obs_noise_position", "obs_noise_velocity", "disturbance_std"):
        _set(cfg, name, _as_float(name, getattr(cfg, name), nonneg=True))
    _set(cfg, "partner_delay", _as_int("partner_delay", cfg.partner_delay, 0))
    _validate_corners(cfg)
    _validate_quadrotor(cfg)


def _validate_leader_path(cfg: PairFlockConfig) -> None:
    """Fields of the ``"climb_and_turn"`` leader (checked whatever the leader type)."""
    if cfg.leader_climb_time is not None:
        _set(
            cfg,
            "leader_climb_time",
            _as_float("leader_climb_time", cfg.leader_climb_time, nonneg=True),
        )
    _set(
        cfg, "leader_level_time", _as_float("leader_level_time", cfg.leader_level_time, nonneg=True)
    )
    turns = cfg.leader_turns
    if isinstance(turns, str) or not isinstance(turns, Sequence):
        raise _bad(
            "leader_turns",
            turns,
            "must be a sequence of (start s, duration s, angle deg) triples",
            TypeError,
        )
    norm: list[tuple[float, float, float]] = []
    for tr in turns:
        if isinstance(tr, str) or not isinstance(tr, Sequence) or len(tr) != 3:
            raise _bad("leader_turns", turns, "each turn must be (start s, duration s, angle deg)")
        start = _as_float("leader_turns start", tr[0], nonneg=True)
        dur = _as_float("leader_turns duration", tr[1], positive=True)
        ang = _as_float("leader_turns angle", tr[2])
        if norm and start < norm[-1][0] + norm[-1][1]:
            raise _bad("leader_turns", turns, "turns must be in time order and must not overlap")
        norm.append((start, dur, ang))
    _set(cfg, "leader_turns", tuple(norm))
    if cfg.leader == "climb_and_turn" and norm and np.hypot(*cfg.leader_velocity[:2]) == 0:
        raise _bad(
            "leader_velocity",
            cfg.leader_velocity,
            "needs a non-zero horizontal part to define a heading for leader_turns",
        )


def _validate_corners(cfg: PairFlockConfig) -> None:
    """With ``init="corners"`` the pair members' fixed start points must be distinct."""
    if cfg.init != "corners":
        return
    from itertools import combinations

    corner = np.broadcast_to(np.asarray(cfg.pair_corner, dtype=np.float64), (cfg.dim,))
    diags = corner_diagonals(cfg.dim)[: len(cfg.pairs)]
    pts = np.concatenate([-diags * corner, diags * corner])
    for i, j in combinations(range(len(pts)), 2):
        d = float(np.linalg.norm(pts[i] - pts[j]))
        if d < max(cfg.min_init_spacing, 1e-9):
            raise _bad(
                "pair_corner",
                cfg.pair_corner,
                f'puts two pair members of init="corners" {d:g} m apart (at least '
                f"min_init_spacing={cfg.min_init_spacing} needed); use non-zero offsets on "
                'more axes or init="random"',
            )


def corner_diagonals(dim: int) -> np.ndarray:
    """Unit-sign diagonals of the cube, (1, 1[, 1]) first; one per pair in 'corners' mode."""
    out = []
    for k in range(2 ** (dim - 1)):
        signs = [1.0] + [(-1.0 if (k >> (dim - 2 - j)) & 1 else 1.0) for j in range(dim - 1)]
        out.append(signs)
    return np.asarray(out)


def _validate_quadrotor(cfg: PairFlockConfig) -> None:
    """The ``quad_*`` fields (always checked, used when ``dynamics="quadrotor"``)."""
    for name in (
        "quad_mass",
        "quad_arm_length",
        "quad_thrust_coeff",
        "quad_torque_coeff",
        "quad_motor_thrust_max",
        "quad_gravity",
        "quad_attitude_freq",
        "quad_attitude_damping",
        "quad_yaw_freq",
        "quad_accel_limit",
    ):
        _set(cfg, name, _as_float(name, getattr(cfg, name), positive=True))
    for name in ("quad_motor_thrust_min", "quad_motor_time_constant", "quad_drag"):
        _set(cfg, name, _as_float(name, getattr(cfg, name), nonneg=True))
    _set(cfg, "quad_yaw", _as_float("quad_yaw", cfg.quad_yaw))
    _set(cfg, "quad_mixer", _as_choice("quad_mixer", cfg.quad_mixer, _QUAD_MIXERS))
    inertia = _as_vector("quad_inertia", cfg.quad_inertia, 3)
    if min(inertia) <= 0:
        raise _bad("quad_inertia", cfg.quad_inertia, "all three moments must be > 0 (kg m^2)")
    _set(cfg, "quad_inertia", inertia)
    hover = cfg.quad_mass * cfg.quad_gravity / 4.0
    if not cfg.quad_motor_thrust_min < hover < cfg.quad_motor_thrust_max:
        raise _bad(
            "quad_motor_thrust_max"
            if hover >= cfg.quad_motor_thrust_max
            else "quad_motor_thrust_min",
            cfg.quad_motor_thrust_max
            if hover >= cfg.quad_motor_thrust_max
            else cfg.quad_motor_thrust_min,
            f"the hover thrust per rotor m g / 4 = {hover:.4g} N must lie strictly between "
            f"quad_motor_thrust_min={cfg.quad_motor_thrust_min} and "
            f"quad_motor_thrust_max={cfg.quad_motor_thrust_max}",
        )
    tilt = _as_float("quad_tilt_limit", cfg.quad_tilt_limit)
    if not 0 < tilt < 90:
        raise _bad("quad_tilt_limit", tilt, "must be in (0, 90) degrees")
    _set(cfg, "quad_tilt_limit", tilt)
    crash = _as_float("quad_crash_tilt", cfg.quad_crash_tilt)
    if not tilt < crash <= 180:
        raise _bad("quad_crash_tilt", crash, f"must be in (quad_tilt_limit={tilt}, 180] degrees")
    _set(cfg, "quad_crash_tilt", crash)
    if cfg.quad_ground_altitude is not None:
        _set(
            cfg, "quad_ground_altitude", _as_float("quad_ground_altitude", cfg.quad_ground_altitude)
        )
    if cfg.dynamics == "quadrotor":
        # explicit integration of the attitude loop needs h * (fastest rate) small
        rate = max(cfg.quad_attitude_freq, cfg.quad_yaw_freq) * max(
            1.0, 2 * cfg.quad_attitude_damping
        )
        h_max = 0.1 / rate
        if cfg.physics_dt > h_max * (1 + 1e-9):
            need = math.ceil(cfg.dt / h_max - 1e-9)
            raise _bad(
                "substeps",
                cfg.substeps,
                f"physics step dt/substeps = {cfg.physics_dt:.4g} s is too coarse for the "
                f"quadrotor attitude loop (needs <= {h_max:.4g} s = 0.1 / {rate:g} rad/s); "
                f"use substeps >= {need} with dt={cfg.dt}",
            )


# ---------------------------------------------------------------------------------------
# presets
# ---------------------------------------------------------------------------------------
PRESETS: dict[str, dict[str, Any]] = {
    # Sec. VI-A with the parameter set of docs/paper-notes.md.
    "paper": dict(
        n_uavs=50,
        dim=2,
        dynamics="particle",
        dt=0.01,
        substeps=1,
        integrator="semi_implicit",
        horizon=50.0,
        spacing=7.0,
        radius=8.4,
        attraction=1.0,
        repulsion=10.0,
        consensus=1.0,
        pinning="all",
        pin_position_gain=0.1,
        pin_velocity_gain=0.632,
        leader="constant_velocity",
        leader_position=25.0,
        leader_velocity=0.5,
        pairs=((0, 1),),
        d_m=5.0,
        surface_slope=4.0,
        pair_accel_limit=1000.0,
        init="corners",
        swarm_half_width=50.0,
        pair_corner=90.0,
        min_init_spacing=2.0,
    ),
}


# Sec. VI-B at quadrotor scale, with the parameter set of docs/paper-notes.md ("Quadrotor
# experiment"): 10 quadrotors, one pair, a leader that climbs, levels off and turns twice.
PRESETS["paper-quadrotor"] = dict(
    n_uavs=10,
    dim=3,
    dynamics="quadrotor",
    dt=0.02,  # protocol and pair action at 50 Hz ...
    substeps=10,  # ... physics and attitude loop at 500 Hz
    integrator="semi_implicit",
    horizon=65.0,
    spacing=3.0,
    radius=3.6,
    attraction=0.3,
    repulsion=3.0,
    consensus=1.0,
    pinning="all",
    pin_position_gain=0.5,
    pin_velocity_gain=1.414,
    leader="climb_and_turn",
    leader_position=(0.0, 0.0, 20.0),
    leader_velocity=(5.0, 0.0, 1.0),  # 5 m/s along +x, climbing at 1 m/s ...
    leader_climb_time=20.0,  # ... until 20 s,
    leader_level_time=2.0,  # levelling off during the first turn
    leader_turns=((20.0, 2.0, 90.0), (50.0, 2.0, 90.0)),
    pairs=((0, 1),),
    d_m=2.5,
    surface_slope=1.0,
    pair_accel_limit=20.0,
    init="corners",
    swarm_center=(0.0, 0.0, 20.0),
    swarm_half_width=(6.0, 6.0, 1.5),
    pair_corner=(10.0, 10.0, 0.0),  # pair at (-10, -10, 20) and (10, 10, 20)
    min_init_spacing=2.0,
    quad_ground_altitude=0.0,
)


def preset_names() -> tuple[str, ...]:
    return tuple(PRESETS)


def make_config(preset: str | None = "paper", **overrides: Any) -> PairFlockConfig:
    """Build a validated config from a preset name plus single-field overrides.

    ``preset=None`` starts from the dataclass defaults. Unknown presets or fields raise
    ``ValueError`` with the valid choices.
    """
    if preset is None:
        base: dict[str, Any] = {}
    else:
        if not isinstance(preset, str) or preset not in PRESETS:
            raise _bad("preset", preset, f"must be one of {', '.join(map(repr, PRESETS))}")
        base = dict(PRESETS[preset])
    _check_names(overrides)
    base.update(overrides)
    base.setdefault("preset", preset)
    return PairFlockConfig(**base)

"""The learning interface's encode and decode in C: what turns the UAV's physical observation
into the network's features, and the network's output into the env action.

A flight controller cannot call Python, so the interface's two transforms
(:class:`~pairflock_env.interfaces.PairInterface` and
:class:`~pairflock_env.interfaces.WorldInterface`) are ported here to C99 float32; the
parity tests (``tests/export``) hold the port to the Python reference within 1e-5 on
recorded observations. Nothing of the layouts is written by hand: every offset is a
``#define`` generated from :class:`~pairflock_env.task.observations.ObsLayout` (the physical
observation, ``PF_OBS_*``) and from ``PairInterface.features`` (the encoded observation,
``PF_FEAT_*``), and every parameter from the interface's stored parameters, so a layout
change reaches the C through the same objects as the Python.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pairflock_env.interfaces import PairInterface, WorldInterface
from pairflock_env.layout import FlatLayout
from pairflock_env.task.spaces import physical_observation_bounds

__all__ = ["PAIR_READS", "interface_source", "layout_defines", "reads"]

#: the physical observation fields the pair interface's encode and decode read
PAIR_READS = (
    "partner_offset",
    "partner_velocity",
    "target_distance",
    "flock_accel",
    "partner_flock_accel",
)
_NEIGHBOR_READS = ("neighbor_offsets", "neighbor_velocities", "neighbor_mask")


def c_float(x: float) -> str:
    """A float32 constant as a C literal that reads back to the same float32."""
    v = float(np.float32(x))
    if np.isinf(v):
        return "INFINITY" if v > 0 else "(-INFINITY)"
    if np.isnan(v):
        raise ValueError("a NaN constant cannot be exported")
    text = str(np.float32(v))  # numpy's shortest text that reads back to the same float32
    if not any(c in text for c in ".e"):
        text += ".0"
    return text + "f"


def reads(interface: Any) -> tuple[str, ...]:
    """The physical observation fields ``interface``'s encode/decode read, in layout order."""
    if isinstance(interface, WorldInterface):
        return interface.layout.names
    names = set(PAIR_READS)
    if interface.params.threat_neighbors:
        names |= set(_NEIGHBOR_READS)
    return tuple(n for n in interface.layout.names if n in names)


def layout_defines(layout: FlatLayout, prefix: str) -> list[str]:
    """``#define PREFIX_NAME offset`` for every field of ``layout``, and its size."""
    lines = [f"#define {prefix}_SIZE {layout.size}"]
    for f in layout:
        lines.append(f"#define {prefix}_{f.name.upper()} {layout.slice(f.name).start}")
    return lines


_PAIR_ENCODE = r"""
static float pf_clip(float x, float lo, float hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

/* sign(x) log(1 + |x|) */
static float pf_symlog(float x)
{
    return x > 0.0f ? log1pf(x) : (x < 0.0f ? -log1pf(-x) : 0.0f);
}

static float pf_norm(const float *x)
{
    float s = 0.0f;
    int i;
    for (i = 0; i < PF_DIM; ++i) s += x[i] * x[i];
    return sqrtf(s);
}

/* The pair frame of the partner offset z: rows e_r, e_t (, e_t2); world axes when z = 0. */
static void pf_basis(const float *z, float R[PF_DIM][PF_DIM])
{
    float r = pf_norm(z);
    int i;
    for (i = 0; i < PF_DIM; ++i) R[0][i] = r > 1e-12f ? z[i] / r : (i == 0 ? 1.0f : 0.0f);
#if PF_DIM == 2
    R[1][0] = -R[0][1];
    R[1][1] = R[0][0];
#else
    {
        float t[3] = {-R[0][1], R[0][0], 0.0f}; /* up x e_r */
        float n = sqrtf(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
        if (!(n > 1e-6f)) { /* e_r vertical: x x e_r */
            t[0] = 0.0f;
            t[1] = -R[0][2];
            t[2] = R[0][1];
        }
        n = sqrtf(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
        for (i = 0; i < 3; ++i) R[1][i] = t[i] / n;
        R[2][0] = R[0][1] * R[1][2] - R[0][2] * R[1][1];
        R[2][1] = R[0][2] * R[1][0] - R[0][0] * R[1][2];
        R[2][2] = R[0][0] * R[1][1] - R[0][1] * R[1][0];
    }
#endif
}

/* y = R x: a world vector in the pair frame */
static void pf_frame(float R[PF_DIM][PF_DIM], const float *x, float *y)
{
    int i, j;
    for (i = 0; i < PF_DIM; ++i) {
        y[i] = 0.0f;
        for (j = 0; j < PF_DIM; ++j) y[i] += R[i][j] * x[j];
    }
}

#if PF_THREATS > 0
/* the threat-ranked neighbour slots: smallest distance at closest approach first */
static void pf_neighbors(const float *obs, float R[PF_DIM][PF_DIM], float *f)
{
    float tca[PF_NEIGHBORS], miss[PF_NEIGHBORS], key[PF_NEIGHBORS], y[PF_DIM];
    int order[PF_NEIGHBORS], k, s, i;
    for (k = 0; k < PF_NEIGHBORS; ++k) {
        const float *x = obs + PF_OBS_NEIGHBOR_OFFSETS + k * PF_DIM;
        const float *w = obs + PF_OBS_NEIGHBOR_VELOCITIES + k * PF_DIM;
        float w2 = 0.0f, xw = 0.0f, m2 = 0.0f, t;
        for (i = 0; i < PF_DIM; ++i) {
            w2 += w[i] * w[i];
            xw += x[i] * w[i];
        }
        t = pf_clip(-xw / (w2 > 1e-9f ? w2 : 1e-9f), 0.0f, PF_TCA_HORIZON);
        for (i = 0; i < PF_DIM; ++i) m2 += (x[i] + w[i] * t) * (x[i] + w[i] * t);
        tca[k] = t;
        miss[k] = sqrtf(m2);
        key[k] = obs[PF_OBS_NEIGHBOR_MASK + k] > 0.0f ? miss[k] : INFINITY;
        /* stable insertion: equal keys keep the layout's nearest-first order */
        for (s = k; s > 0 && key[order[s - 1]] > key[k]; --s) order[s] = order[s - 1];
        order[s] = k;
    }
    for (s = 0; s < PF_THREATS; ++s) {
        float m = obs[PF_OBS_NEIGHBOR_MASK + order[s]];
        k = order[s];
        pf_frame(R, obs + PF_OBS_NEIGHBOR_OFFSETS + k * PF_DIM, y);
        for (i = 0; i < PF_DIM; ++i)
            f[PF_FEAT_NEIGHBOR_OFFSETS + s * PF_DIM + i] =
                pf_clip(y[i] / PF_NEIGHBOR_SCALE, -PF_CLIP, PF_CLIP) * m;
        pf_frame(R, obs + PF_OBS_NEIGHBOR_VELOCITIES + k * PF_DIM, y);
        for (i = 0; i < PF_DIM; ++i)
            f[PF_FEAT_NEIGHBOR_VELOCITIES + s * PF_DIM + i] =
                pf_clip(y[i] / PF_VELOCITY_SCALE, -PF_CLIP, PF_CLIP) * m;
        f[PF_FEAT_NEIGHBOR_MASK + s] = m;
        f[PF_FEAT_NEIGHBOR_TCA + s] = tca[k] / PF_TCA_HORIZON * m;
        f[PF_FEAT_NEIGHBOR_MISS + s] =
            (miss[k] / PF_NEIGHBOR_SCALE < PF_CLIP ? miss[k] / PF_NEIGHBOR_SCALE : PF_CLIP) * m;
    }
}
#endif

void pairflock_policy_encode(const float *observation, float *features)
{
    const float *obs = observation;
    const float *fi = obs + PF_OBS_FLOCK_ACCEL, *fj = obs + PF_OBS_PARTNER_FLOCK_ACCEL;
    float R[PF_DIM][PF_DIM], y[PF_DIM], d[PF_DIM], e;
    float *f = features;
    int i;
    pf_basis(obs + PF_OBS_PARTNER_OFFSET, R);
    e = pf_norm(obs + PF_OBS_PARTNER_OFFSET) - obs[PF_OBS_TARGET_DISTANCE];
    f[PF_FEAT_ERROR] = pf_clip(e / PF_POSITION_SCALE, -PF_CLIP, PF_CLIP);
    f[PF_FEAT_ERROR_FINE] = pf_symlog(e / PF_FINE_POSITION) / PF_SYMLOG_DIV;
    pf_frame(R, obs + PF_OBS_PARTNER_VELOCITY, y);
    for (i = 0; i < PF_DIM; ++i) {
        f[PF_FEAT_REL_VELOCITY + i] = pf_clip(y[i] / PF_VELOCITY_SCALE, -PF_CLIP, PF_CLIP);
        f[PF_FEAT_REL_VELOCITY_FINE + i] = pf_symlog(y[i] / PF_FINE_VELOCITY) / PF_SYMLOG_DIV;
        d[i] = fj[i] - fi[i];
    }
    pf_frame(R, d, y);
    for (i = 0; i < PF_DIM; ++i)
        f[PF_FEAT_FLOCK_DIFFERENCE + i] = pf_clip(y[i] / PF_MAX_ACCEL, -PF_CLIP, PF_CLIP);
    pf_frame(R, fi, y);
    for (i = 0; i < PF_DIM; ++i)
        f[PF_FEAT_FLOCK_ACCEL + i] = pf_clip(y[i] / PF_MAX_ACCEL, -PF_CLIP, PF_CLIP);
#if PF_THREATS > 0
    pf_neighbors(obs, R, f);
#endif
    for (i = 0; i < PF_FEAT_SIZE; ++i) f[i] = pf_clip(f[i], -PF_CLIP, PF_CLIP);
}

void pairflock_policy_decode(const float *observation, const float *net_action, float *action)
{
    const float *obs = observation;
    float R[PF_DIM][PF_DIM], a[PF_DIM], u[PF_DIM], over;
    int i, j;
    pf_basis(obs + PF_OBS_PARTNER_OFFSET, R);
    for (i = 0; i < PF_DIM; ++i) a[i] = pf_clip(net_action[i], -1.0f, 1.0f);
    for (i = 0; i < PF_DIM; ++i) {
        float s = 0.0f;
        for (j = 0; j < PF_DIM; ++j) s += R[j][i] * a[j]; /* R^T a */
        u[i] = PF_ACCEL_SCALE * s;
#if PF_FEEDFORWARD
        u[i] += 0.5f * (obs[PF_OBS_PARTNER_FLOCK_ACCEL + i] - obs[PF_OBS_FLOCK_ACCEL + i]);
#endif
    }
    over = pf_norm(u) / PF_BOUND;
    if (over < 1.0f) over = 1.0f;
    for (i = 0; i < PF_DIM; ++i) action[i] = u[i] / (PF_PAIR_ACCEL_LIMIT * over);
}
"""

_WORLD = r"""
static const float pf_obs_low[PF_OBS_SIZE] = {%(low)s};
static const float pf_obs_high[PF_OBS_SIZE] = {%(high)s};

void pairflock_policy_encode(const float *observation, float *features)
{
    int i;
    for (i = 0; i < PF_OBS_SIZE; ++i) {
        float x = observation[i];
        features[i] = x < pf_obs_low[i] ? pf_obs_low[i] : (x > pf_obs_high[i] ? pf_obs_high[i] : x);
    }
}

void pairflock_policy_decode(const float *observation, const float *net_action, float *action)
{
    int i;
    (void)observation;
    for (i = 0; i < PF_DIM; ++i) action[i] = net_action[i];
}
"""


def _pair_constants(it: PairInterface) -> list[str]:
    p, cfg = it.params, it.config
    consts = {
        "PF_NEIGHBORS": str(cfg.obs_neighbors),
        "PF_THREATS": str(p.threat_neighbors),
        "PF_FEEDFORWARD": "1" if p.feedforward else "0",
        "PF_CLIP": c_float(it.observation_bound),
        "PF_SYMLOG_DIV": c_float(8.0),
        "PF_POSITION_SCALE": c_float(p.position_scale),
        "PF_VELOCITY_SCALE": c_float(p.velocity_scale),
        "PF_FINE_POSITION": c_float(p.fine_position),
        "PF_FINE_VELOCITY": c_float(p.fine_velocity),
        "PF_NEIGHBOR_SCALE": c_float(p.neighbor_scale),
        "PF_TCA_HORIZON": c_float(p.tca_horizon),
        "PF_MAX_ACCEL": c_float(p.max_accel),
        "PF_ACCEL_SCALE": c_float(p.accel_scale),
        "PF_BOUND": c_float(min(p.max_accel, cfg.pair_accel_limit)),
    }
    return [f"#define {k} {v}" for k, v in consts.items()]


def _floats(values: np.ndarray) -> str:
    items = [c_float(v) for v in np.asarray(values, np.float32)]
    return ",\n    ".join(", ".join(items[i : i + 6]) for i in range(0, len(items), 6))


def interface_source(interface: Any) -> str:
    """The C of ``interface``'s encode and decode: the layout and parameter ``#define``s,
    then ``pairflock_policy_encode`` and ``pairflock_policy_decode``."""
    cfg = interface.config
    lines = [
        f"#define PF_DIM {cfg.dim}",
        f"#define PF_PAIR_ACCEL_LIMIT {c_float(cfg.pair_accel_limit)}",
        "/* the physical observation (ObsLayout): offset of each field */",
        *layout_defines(interface.layout, "PF_OBS"),
    ]
    if isinstance(interface, PairInterface):
        lines += ["/* the encoded observation (PairInterface.features) */"]
        lines += layout_defines(interface.features, "PF_FEAT")
        lines += ["/* the interface's parameters (stored with the model) */"]
        return "\n".join([*lines, *_pair_constants(interface), _PAIR_ENCODE])
    if isinstance(interface, WorldInterface):
        low, high = physical_observation_bounds(cfg)
        body = _WORLD % {"low": _floats(low), "high": _floats(high)}
        return "\n".join([*lines, "#define PF_FEAT_SIZE PF_OBS_SIZE", body])
    raise TypeError(f"interface {interface!r} is invalid: the C port covers 'pair' and 'world'")

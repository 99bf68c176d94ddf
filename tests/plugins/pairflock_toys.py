"""A toy plug-in of each seam, registered from outside the package (docs/extending.md shows
this file; tests/test_plugins.py loads it with ``PAIRFLOCK_PLUGINS=pairflock_toys``).

Importing it registers a vehicle model ``"toy_dragged"``, a safety filter ``"toy_clip"``, a
leader trajectory ``"toy_circle"`` and an observation field ``"toy_leader_distance"``, each
with the config parameters it declares.
"""

from __future__ import annotations

import math

import numpy as np

from pairflock_env.config.fields import Field, Real
from pairflock_env.config.schema import Section
from pairflock_env.dynamics import VEHICLES
from pairflock_env.dynamics.vehicle import Vehicle
from pairflock_env.safety import FILTERS, Filter
from pairflock_env.swarm.leader import LEADERS, Leader
from pairflock_env.task.observations import OBSERVATIONS, ObservationField
from pairflock_env.task.spaces import leader_bounds


# --8<-- [start:vehicle]
class DraggedParticle:
    """A double integrator with linear air drag, p' = a_des - c p (c = ``toy_drag``, 1/s)."""

    def __init__(self, config, num_swarms):
        self.h, self.substeps, self.drag = config.physics_dt, config.substeps, config.toy_drag

    def reset_rows(self, rows, q, p):
        pass  # no state of its own

    def advance(self, q, p, a_des):
        for _ in range(self.substeps):  # semi-implicit Euler, in place
            p += (a_des - self.drag * p) * self.h
            q += p * self.h

    def info(self):
        return {}


VEHICLES.register(
    Vehicle(
        name="toy_dragged",
        doc="double integrator with linear drag",
        section=Section(
            "toy_dragged",
            "Toy dragged particle",
            'Used with dynamics="toy_dragged".',
            (Field("toy_drag", Real(0.0, 100.0), 0.1, "1/s", "Drag coefficient c."),),
        ),
        model=DraggedParticle,
    )
)
# --8<-- [end:vehicle]


# --8<-- [start:filter]
class ClipStage:
    """Scales each paired UAV's pair command down to at most ``toy_clip_accel`` (m/s^2)."""

    def __init__(self, config, agent_uavs, num_swarms, partner_uavs):
        self.limit = config.toy_clip_accel
        self.last = np.zeros((num_swarms, len(agent_uavs)))

    def apply(self, q, p, flock_acc, u, grid=None):
        norm = np.linalg.norm(u, axis=-1, keepdims=True)
        scale = np.minimum(1.0, self.limit / np.maximum(norm, 1e-300))
        self.last = (norm * (1.0 - scale))[..., 0]  # how much each command was cut
        return u * scale

    def info(self, reset=False):
        cut = np.zeros_like(self.last) if reset else self.last.copy()
        return {
            "safety_active": cut > 0,
            "safety_correction": cut,
            "safety_infeasible": np.zeros(cut.shape, bool),
        }


FILTERS.register(
    Filter(
        name="toy_clip",
        doc="a bound on the pair command's norm",
        section=Section(
            "toy_clip",
            "Toy clipping filter",
            'Used with safety_filter="toy_clip".',
            (Field("toy_clip_accel", Real(0.0, 1e6), 20.0, "m/s^2", "Largest pair command."),),
        ),
        stage=ClipStage,
    )
)
# --8<-- [end:filter]


# --8<-- [start:leader]
class CircleLeader:
    """Circles ``leader_position`` at radius ``toy_circle_radius`` with period
    ``toy_circle_period`` in the first two axes."""

    def __init__(self, config):
        self.q0 = config.vector("leader_position")
        self.r, self.w = config.toy_circle_radius, 2 * math.pi / config.toy_circle_period
        self.dim = config.dim

    def state(self, t):
        a = self.w * np.asarray(t, dtype=np.float64)
        q = np.tile(self.q0, (len(a), 1))
        p = np.zeros_like(q)
        q[:, 0] += self.r * np.cos(a)
        q[:, 1] += self.r * np.sin(a)
        p[:, 0], p[:, 1] = -self.r * self.w * np.sin(a), self.r * self.w * np.cos(a)
        return q, p


def _circle_speed(config):
    v = np.zeros(config.dim)
    v[:2] = config.toy_circle_radius * 2 * math.pi / config.toy_circle_period
    return v


LEADERS.register(
    Leader(
        name="toy_circle",
        doc="a circle around leader_position",
        section=Section(
            "toy_circle",
            "Toy circling leader",
            'Used with leader="toy_circle".',
            (
                Field("toy_circle_radius", Real(0.0, 1e4), 30.0, "m", "Radius of the circle."),
                Field("toy_circle_period", Real(1.0, 1e6), 60.0, "s", "Time of one lap."),
            ),
        ),
        trajectory=CircleLeader,
        speed_bound=_circle_speed,
    )
)
# --8<-- [end:leader]


# --8<-- [start:observation]
def _leader_distance(ctx):
    """Each agent's distance to the virtual leader (B, M, 1), m."""
    off = ctx.leader_q[:, None, :] - ctx.q[:, ctx.agent_uavs]
    return np.linalg.norm(off, axis=-1, keepdims=True)


def _leader_distance_bound(config):
    lq, _ = leader_bounds(config)  # |leader position| per axis over an episode
    return float(np.linalg.norm(lq + config.divergence_limit))


OBSERVATIONS.register(
    ObservationField(
        name="toy_leader_distance",
        doc="distance from the observing UAV to the virtual leader",
        shape=lambda dim, k: (1,),
        unit="m",
        value=_leader_distance,
        bound=_leader_distance_bound,
    )
)
# --8<-- [end:observation]

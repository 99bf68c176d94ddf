"""The square-law sliding-mode pair controller of Sec. IV (eqs. 24-28).

With y the partner offset and y' the relative velocity seen by one UAV,

    E = y.y,  F = y'.y',  s = c (E - d_m^2) + 2 y.y'                       (24-26)
    f^x = 1/2 (a N y + b N y' - c y' - (F/E) y - k sign(y) sw(s))           (28)

where N is the number of neighbours the pair shares (plus 2 when the two are neighbours of
each other), a the attraction slope and b the consensus weight of the flocking protocol,
sign(y) is element-wise and sw(s) = sign(s) (the paper) or sat(s / phi) with a boundary layer
phi. UAV B applies +f^x and UAV A -f^x (y = q_B - q_A); since f^x is odd in (y, y'), each
UAV applies -f^x(partner offset, partner velocity) from its own observation, without knowing
its role. Then s' = -2 k ||y||_1 sw(s) + 2 y.delta, delta being the part of the flocking
difference the a N y + b N y' terms do not cancel (docs/paper-notes.md, erratum 1).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from baselines.controllers.base import PairPolicy, gain_value
from pairflock_env.task.pairing import sliding_surface

__all__ = ["SMC_DEFAULTS", "SlidingModeController"]

#: default (c, k) per preset; c defaults to the env's surface_slope
SMC_DEFAULTS: dict[str | None, dict[str, float]] = {
    "paper": {"k": 300.0},
    # quadrotor scale (docs/paper-notes.md): c = 1 comes from the preset's surface_slope;
    # k = 6 stalls behind a wedged UAV in some seeds, k = 10 does not
    "paper-quadrotor": {"k": 10.0},
}


class SlidingModeController(PairPolicy):
    """Eq. 28 with the errata of docs/paper-notes.md; see the module docstring."""

    GAINS = {
        "c": (None, "surface slope c of eq. 26 (1/s); default: the env's surface_slope"),
        "k": (
            None,
            "switching gain k (m/s^2); default: SMC_DEFAULTS of the preset "
            "(300 for paper, 10 for paper-quadrotor)",
        ),
        "a": (None, "attraction slope in the a N y term; default: the env's attraction"),
        "b": (None, "consensus weight in the b N y' term; default: the env's consensus"),
        "boundary_layer": (None, "phi (m^2/s) for sat(s/phi); None uses sign(s) as the paper"),
    }

    def __init__(self, env: Any, **gains: Any) -> None:
        super().__init__(env, **gains)
        cfg = self.config
        g = self.gains
        if g["c"] is None:
            g["c"] = cfg.surface_slope
        if g["k"] is None:
            g["k"] = SMC_DEFAULTS.get(cfg.preset, SMC_DEFAULTS["paper"])["k"]
        g["a"] = cfg.attraction if g["a"] is None else g["a"]
        g["b"] = cfg.consensus if g["b"] is None else g["b"]
        for name in ("c", "k"):
            g[name] = gain_value(name, g[name], minimum=0.0, allow_minimum=False)
        for name in ("a", "b"):
            g[name] = gain_value(name, g[name], minimum=0.0, allow_minimum=True)
        if g["boundary_layer"] is not None:
            g["boundary_layer"] = gain_value(
                "boundary_layer", g["boundary_layer"], minimum=0.0, allow_minimum=False
            )

    def pair_term(self, y: np.ndarray, ydot: np.ndarray, n_shared: np.ndarray, d_m: np.ndarray):
        """f^x of eq. 28 (m/s^2) for offset y, rate y', shared count N (..., 1), d_m (...)."""
        g = self.gains
        a, b, c, k, phi = g["a"], g["b"], g["c"], g["k"], g["boundary_layer"]
        E = np.sum(y * y, axis=-1, keepdims=True)
        F = np.sum(ydot * ydot, axis=-1, keepdims=True)
        s = sliding_surface(y, ydot, d_m, c)[..., None]
        sw = np.sign(s) if phi is None else np.clip(s / phi, -1.0, 1.0)
        ratio = F / np.maximum(E, 1e-12)
        return 0.5 * (
            a * n_shared * y + b * n_shared * ydot - c * ydot - ratio * y - k * np.sign(y) * sw
        )

    def accel(self, obs: np.ndarray) -> np.ndarray:
        L = self.layout
        y = L.get(obs, "partner_offset")
        yd = L.get(obs, "partner_velocity")
        n = L.get(obs, "shared_neighbors")
        dm = L.get(obs, "target_distance")[..., 0]
        return -self.pair_term(y, yd, n, dm)

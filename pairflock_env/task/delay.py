"""The partner delay: what each agent knows of its partner is ``partner_delay`` control steps
old (position, velocity and flocking command alike); its own state is always current."""

from __future__ import annotations

import numpy as np

__all__ = ["PartnerDelayBuffer"]


class PartnerDelayBuffer:
    """Ring buffer of every agent's (q, p, flocking command) over the last ``delay`` + 1
    control steps, read back as each agent's partner's sample from ``delay`` steps ago.

    Args:
        delay: the delay d in control steps (>= 1).
        num_swarms, n_agents, dim: B, M and dim of the samples.
        partner_col: agent column of each agent's partner (M,).

    A freshly reset swarm has no older samples, so its whole history is filled with the
    reset state: until d steps have passed, agents see their partner's reset state.
    Memory: 3 (d + 1) B M dim float64 values.
    """

    def __init__(
        self, delay: int, num_swarms: int, n_agents: int, dim: int, partner_col: np.ndarray
    ) -> None:
        if delay < 1:
            raise ValueError(f"delay={delay!r} is invalid: must be >= 1 control step")
        self.delay = int(delay)
        self._hist = np.zeros((3, self.delay + 1, num_swarms, n_agents, dim))
        self._pos = 0
        self._partner_col = np.asarray(partner_col)

    def push(self, now: np.ndarray, reset_rows: np.ndarray | None = None) -> np.ndarray:
        """Record this control step's samples and read the delayed partner samples.

        Args:
            now: (3, B, M, dim): each agent's own q, p and flocking command now.
            reset_rows: ``None`` for a control step (the buffer advances); at a reset, the
                rows being reset (the buffer does not advance, those rows' history is
                refilled with ``now``).

        Returns:
            (3, B, M, dim): each agent's partner's q, p and flocking command ``delay``
            control steps ago.
        """
        H = self._hist.shape[1]
        if reset_rows is None:
            self._pos = (self._pos + 1) % H
        self._hist[:, self._pos] = now
        if reset_rows is not None:  # a fresh episode has no older samples
            self._hist[:, :, reset_rows] = now[:, None, reset_rows]
        return self._hist[:, (self._pos + 1) % H][:, :, self._partner_col]

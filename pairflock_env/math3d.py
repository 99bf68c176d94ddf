"""Rotations in 3-D: hat/vee, the SO(3) exponential map, Euler angles.

Conventions: a rotation matrix R maps body-frame vectors to the world frame (x forward,
y left, z up); its columns are the body axes in world coordinates. Angles are in radians.

    hat(w) v = w x v                         hat: R^3 -> so(3), vee its inverse
    exp(hat(phi)) = I + A hat(phi) + B hat(phi)^2,                       (Rodrigues)
        A = sin(theta) / theta,  B = (1 - cos(theta)) / theta^2,  theta = ||phi||
    ZYX Euler angles (yaw psi, pitch theta, roll phi):  R = Rz(psi) Ry(theta) Rx(phi)

The exponential map is written once, as a numba scalar function (``so3_exp_scalar``) that the
quadrotor kernel calls per UAV and per physics step; :func:`so3_exp` applies the same function
over arrays of any leading shape. An exponential-map update ``R <- R exp(hat(w h))`` multiplies
R by an exact rotation, so R leaves SO(3) only by floating-point rounding (about 1e-15 per
step, a random walk), unlike a first-order update ``R <- R (I + hat(w h))``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "euler_zyx",
    "hat",
    "orthonormality_error",
    "rotation_zyx",
    "so3_exp",
    "so3_exp_scalar",
    "vee",
]


def hat(w: np.ndarray) -> np.ndarray:
    """Skew-symmetric matrices (..., 3, 3) of vectors w (..., 3): hat(w) v = w x v."""
    w = np.asarray(w, dtype=np.float64)
    if w.shape[-1:] != (3,):
        raise ValueError(f"w has shape {w.shape}; expected (..., 3)")
    out = np.zeros((*w.shape[:-1], 3, 3))
    out[..., 0, 1] = -w[..., 2]
    out[..., 0, 2] = w[..., 1]
    out[..., 1, 0] = w[..., 2]
    out[..., 1, 2] = -w[..., 0]
    out[..., 2, 0] = -w[..., 1]
    out[..., 2, 1] = w[..., 0]
    return out


def vee(S: np.ndarray) -> np.ndarray:
    """Vectors (..., 3) of skew-symmetric matrices S (..., 3, 3) (the inverse of :func:`hat`;
    the skew part of S is used, so vee(M) = vee((M - M^T) / 2) for any M)."""
    S = np.asarray(S, dtype=np.float64)
    if S.shape[-2:] != (3, 3):
        raise ValueError(f"S has shape {S.shape}; expected (..., 3, 3)")
    return 0.5 * np.stack(
        [S[..., 2, 1] - S[..., 1, 2], S[..., 0, 2] - S[..., 2, 0], S[..., 1, 0] - S[..., 0, 1]],
        axis=-1,
    )


@njit(cache=True, inline="always")
def so3_exp_scalar(x, y, z):
    """exp(hat((x, y, z))) as a 9-tuple in row-major order (Rodrigues' formula; a Taylor
    expansion below theta = 1e-4 keeps full precision for tiny rotations)."""
    t2 = x * x + y * y + z * z
    if t2 < 1e-8:
        a = 1.0 - t2 / 6.0 + t2 * t2 / 120.0
        b = 0.5 - t2 / 24.0 + t2 * t2 / 720.0
    else:
        t = np.sqrt(t2)
        a = np.sin(t) / t
        b = (1.0 - np.cos(t)) / t2
    # I + a hat + b hat^2, with hat^2 = w w^T - t2 I
    return (
        1.0 + b * (x * x - t2),
        -a * z + b * x * y,
        a * y + b * x * z,
        a * z + b * x * y,
        1.0 + b * (y * y - t2),
        -a * x + b * y * z,
        -a * y + b * x * z,
        a * x + b * y * z,
        1.0 + b * (z * z - t2),
    )


@njit(cache=True)
def _so3_exp_rows(phi, out):
    for i in range(phi.shape[0]):
        r = so3_exp_scalar(phi[i, 0], phi[i, 1], phi[i, 2])
        for k in range(9):
            out[i, k] = r[k]


def so3_exp(phi: np.ndarray) -> np.ndarray:
    """Rotation matrices exp(hat(phi)) (..., 3, 3) of rotation vectors phi (..., 3)."""
    phi = np.asarray(phi, dtype=np.float64)
    if phi.shape[-1:] != (3,):
        raise ValueError(f"phi has shape {phi.shape}; expected (..., 3)")
    flat = np.ascontiguousarray(phi.reshape(-1, 3))
    out = np.empty((flat.shape[0], 9))
    _so3_exp_rows(flat, out)
    return out.reshape((*phi.shape[:-1], 3, 3))


def euler_zyx(R: np.ndarray) -> np.ndarray:
    """(roll, pitch, yaw) (..., 3) in radians of rotation matrices R (..., 3, 3), ZYX order
    (R = Rz(yaw) Ry(pitch) Rx(roll)); pitch in [-pi/2, pi/2]."""
    R = np.asarray(R, dtype=np.float64)
    if R.shape[-2:] != (3, 3):
        raise ValueError(f"R has shape {R.shape}; expected (..., 3, 3)")
    roll = np.arctan2(R[..., 2, 1], R[..., 2, 2])
    pitch = -np.arcsin(np.clip(R[..., 2, 0], -1.0, 1.0))
    yaw = np.arctan2(R[..., 1, 0], R[..., 0, 0])
    return np.stack([roll, pitch, yaw], axis=-1)


def rotation_zyx(roll, pitch, yaw) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll) for arrays of angles (broadcast), shape (..., 3, 3)."""
    roll, pitch, yaw = np.broadcast_arrays(
        *(np.asarray(a, dtype=np.float64) for a in (roll, pitch, yaw))
    )
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    R = np.empty((*roll.shape, 3, 3))
    R[..., 0, 0] = cy * cp
    R[..., 0, 1] = cy * sp * sr - sy * cr
    R[..., 0, 2] = cy * sp * cr + sy * sr
    R[..., 1, 0] = sy * cp
    R[..., 1, 1] = sy * sp * sr + cy * cr
    R[..., 1, 2] = sy * sp * cr - cy * sr
    R[..., 2, 0] = -sp
    R[..., 2, 1] = cp * sr
    R[..., 2, 2] = cp * cr
    return R


def orthonormality_error(R: np.ndarray) -> np.ndarray:
    """max |R^T R - I| entry-wise (the max-norm of the defect), over the last two axes."""
    R = np.asarray(R, dtype=np.float64)
    RtR = np.einsum("...ji,...jk->...ik", R, R)
    return np.max(np.abs(RtR - np.eye(3)), axis=(-2, -1))

"""Small helpers on homogeneous transforms (private, batch over leading axes)."""

from __future__ import annotations

import numpy as np

from ._typing import FloatArray


def invert_transform(T: FloatArray) -> FloatArray:
    """Inverse of rigid transforms ``[[R, t], [0, 1]]`` of shape (..., 4, 4)."""
    R = T[..., :3, :3]
    Rt = np.swapaxes(R, -1, -2)
    out = np.zeros(T.shape)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -(Rt @ T[..., :3, 3, None])[..., 0]
    out[..., 3, 3] = 1.0
    return out


def transform_from_rotation_translation(R: FloatArray, t: FloatArray
                                        ) -> FloatArray:
    """Assemble ``[[R, t], [0, 1]]`` from (..., 3, 3) and (..., 3), broadcasting."""
    shape = np.broadcast_shapes(R.shape[:-2], t.shape[:-1])
    T = np.zeros(shape + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = t
    T[..., 3, 3] = 1.0
    return T


def rot_x(a: FloatArray) -> FloatArray:
    """Rotation about x by ``a`` (..., 3, 3)."""
    a = np.asarray(a, float)
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.stack([o, z, z, z, c, -s, z, s, c], axis=-1).reshape(c.shape + (3, 3))


def rot_y(a: FloatArray) -> FloatArray:
    """Rotation about y by ``a`` (..., 3, 3)."""
    a = np.asarray(a, float)
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.stack([c, z, s, z, o, z, -s, z, c], axis=-1).reshape(c.shape + (3, 3))


def rot_z(a: FloatArray) -> FloatArray:
    """Rotation about z by ``a`` (..., 3, 3)."""
    a = np.asarray(a, float)
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.stack([c, -s, z, s, c, z, z, z, o], axis=-1).reshape(c.shape + (3, 3))


def wrap_angle(a: FloatArray) -> FloatArray:
    """Angles mapped to ``(-pi, pi]`` (values already in that range are returned unchanged)."""
    a = np.asarray(a, float)
    inside = (a > -np.pi) & (a <= np.pi)
    w = np.mod(a + np.pi, 2 * np.pi) - np.pi
    return np.where(inside, a, np.where(w <= -np.pi, w + 2 * np.pi, w))

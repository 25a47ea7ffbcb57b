"""Quaternion order converters and scipy Rotation interop (issue 12.10)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import athenakin as ak
from athenakin.study import (
    quaternion_from_rotation,
    quaternion_from_scipy_rotation,
    quaternion_wxyz_from_xyzw,
    quaternion_xyzw_from_wxyz,
    rotation_from_quaternion,
    scipy_rotation_from_quaternion,
)

SEED = 1212
RNG_QUATS = np.random.default_rng(SEED).normal(size=(500, 4))


def test_order_converters_are_inverse_and_reorder_only():
    x = RNG_QUATS.reshape(5, 100, 4)
    y = quaternion_xyzw_from_wxyz(x)
    assert y.shape == x.shape
    np.testing.assert_array_equal(y[..., 3], x[..., 0])
    np.testing.assert_array_equal(y[..., :3], x[..., 1:])
    np.testing.assert_array_equal(quaternion_wxyz_from_xyzw(y), x)


@pytest.mark.parametrize(("wxyz", "xyzw"), [
    ([1, 0, 0, 0], [0, 0, 0, 1]),
    ([0, 1, 0, 0], [1, 0, 0, 0]),
    ([0.5, 0.5, 0.5, 0.5], [0.5, 0.5, 0.5, 0.5]),
    ([0.1, 0.2, 0.3, 0.4], [0.2, 0.3, 0.4, 0.1]),
])
def test_order_table(wxyz, xyzw):
    np.testing.assert_array_equal(quaternion_xyzw_from_wxyz(wxyz), xyzw)
    np.testing.assert_array_equal(quaternion_wxyz_from_xyzw(xyzw), wxyz)


def test_scipy_rotation_agrees_with_eq3_and_shepperd():
    """The core's own conversions (numpy, Eq. 3) match scipy's, sign aside."""
    R_ours = rotation_from_quaternion(RNG_QUATS)
    r = scipy_rotation_from_quaternion(RNG_QUATS)
    np.testing.assert_allclose(r.as_matrix(), R_ours, rtol=0, atol=1e-14)
    x = quaternion_from_rotation(R_ours)
    x_scipy = quaternion_from_scipy_rotation(Rotation.from_matrix(R_ours))
    sign = np.sign(np.sum(x * x_scipy, axis=-1, keepdims=True))
    np.testing.assert_allclose(x, sign * x_scipy, rtol=0, atol=1e-14)


def test_round_trip_through_scipy():
    x = RNG_QUATS / np.linalg.norm(RNG_QUATS, axis=-1, keepdims=True)
    back = quaternion_from_scipy_rotation(scipy_rotation_from_quaternion(x))
    sign = np.sign(np.sum(x * back, axis=-1, keepdims=True))
    np.testing.assert_allclose(sign * back, x, rtol=0, atol=1e-15)
    single = scipy_rotation_from_quaternion(x[0])
    assert single.single and quaternion_from_scipy_rotation(single).shape == (4,)
    assert len(scipy_rotation_from_quaternion(x.reshape(10, 50, 4))) == 500


def test_fk_frame_to_scipy_and_ros_order():
    d = ak.Design.default()
    sol = ak.forward_kinematics(ak.robot.REFERENCE_Q, ak.default_rcm_frame(d), d)
    R = sol.T_b_s[0, :3, :3]
    xyzw = quaternion_xyzw_from_wxyz(quaternion_from_rotation(R))
    np.testing.assert_allclose(Rotation.from_quat(xyzw).as_matrix(), R, rtol=0, atol=1e-14)


def test_errors():
    with pytest.raises(ak.InvalidInputError, match="q_wxyz"):
        quaternion_xyzw_from_wxyz([1.0, 0.0, 0.0])
    with pytest.raises(ak.InvalidInputError, match="q_xyzw"):
        quaternion_wxyz_from_xyzw([np.nan, 0.0, 0.0, 1.0])
    with pytest.raises(TypeError, match="scipy.spatial.transform.Rotation"):
        quaternion_from_scipy_rotation(np.eye(3))


def test_calibration_rotation_vector_is_scipy_rodrigues():
    """calibration's exp([omega]_x) (now scipy's) matches Rodrigues' formula, small angles too."""
    from athenakin.calibration._model import rotation_from_vector

    rng = np.random.default_rng(SEED + 1)
    cases = [*rng.normal(size=(50, 3)), np.zeros(3), np.array([1e-10, 0.0, 0.0]),
             np.pi * np.eye(3)[1]]
    for w in cases:
        th = np.linalg.norm(w)
        K = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
        ref = (np.eye(3) + K + 0.5 * K @ K if th < 1e-8 else
               np.eye(3) + np.sin(th) / th * K + (1 - np.cos(th)) / th ** 2 * K @ K)
        np.testing.assert_allclose(rotation_from_vector(w), ref, rtol=0, atol=1e-14)


def test_zero_quaternion_named():
    """Audit of issue 13: a zero quaternion is InvalidInputError naming ``x`` (was scipy's)."""
    with pytest.raises(ak.InvalidInputError, match="x: expected non-zero"):
        scipy_rotation_from_quaternion(np.zeros((2, 4)))

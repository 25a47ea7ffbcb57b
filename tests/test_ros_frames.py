"""athenakin.ros frames: joint values and link poses of many readings against the reference code."""

import numpy as np
import pytest

import athenakin as ak
from athenakin.ros._frames import (
    MOVING_LINKS,
    joint_values,
    link_poses,
    quaternion_xyzw,
    urdf_model,
)
from athenakin.sim import CLOSURE_PAIRS, JOINTS, mechanism_joint_values

D = ak.Design.default()
T = ak.default_rcm_frame(D)


def _samples(n, seed):
    """Seeded random q near the reference, with every valid FK slot of each."""
    rng = np.random.default_rng(seed)
    q = np.array(ak.robot.REFERENCE_Q) + rng.uniform(-0.04, 0.04, (n, 3))
    sol = ak.forward_kinematics(q, T, D)
    rows, slots = np.nonzero(sol.valid)
    return q, sol, rows, slots


@pytest.mark.parametrize("seed", [0, 1])
def test_joint_values_and_link_poses_match_the_reference_in_every_slot(seed):
    q, sol, rows, slots = _samples(6, seed)
    assert len(set(slots.tolist())) > 4                 # both modes, several branches
    model = urdf_model(D, T)
    jv = joint_values(model, q[rows], sol.p[rows, slots], sol.u[rows, slots],
                      sol.T_b_s[rows, slots, :3, 3])
    poses = link_poses(model, jv)
    for k, (i, s) in enumerate(zip(rows, slots, strict=True)):
        ref = mechanism_joint_values(q[i], T, D, slot=int(s))
        got = np.array([jv[name][k] for name in JOINTS])
        want = np.array([ref.urdf[name] for name in JOINTS])
        d = np.abs(np.angle(np.exp(1j * (got - want))))     # angles modulo 2 pi
        assert d.max() < 1e-12, (i, s, dict(zip(JOINTS, got - want, strict=True)))
        np.testing.assert_allclose(poses["tool_tip"][k], sol.T_b_tip[i, s], rtol=0, atol=1e-12)
        # the tree's loop closures hold: each closure pair coincides
        for a, b in CLOSURE_PAIRS:
            np.testing.assert_allclose(poses[a][k, :3, 3], poses[b][k, :3, 3], rtol=0,
                                       atol=1e-12)
        np.testing.assert_allclose(poses["sph_5_frame"][k], T, rtol=0, atol=1e-12)
    assert set(MOVING_LINKS) <= set(poses)


def test_batch_equals_loop():
    q, sol, rows, slots = _samples(4, 5)
    model = urdf_model(D, T)
    args = (q[rows], sol.p[rows, slots], sol.u[rows, slots], sol.T_b_s[rows, slots, :3, 3])
    batch = link_poses(model, joint_values(model, *args))
    for k in range(len(rows)):
        one = link_poses(model, joint_values(model, *(a[k:k + 1] for a in args)))
        for name in batch:
            np.testing.assert_array_equal(one[name][0], batch[name][k])


def test_quaternions_against_scipy_and_round_trip():
    Rotation = pytest.importorskip("scipy.spatial.transform").Rotation
    R = Rotation.random(2000, random_state=7)
    mats = R.as_matrix()
    # named edge cases: identity, half turns about each axis (w = 0), near half turns
    extra = [np.eye(3), np.diag([1.0, -1.0, -1.0]), np.diag([-1.0, 1.0, -1.0]),
             np.diag([-1.0, -1.0, 1.0]),
             Rotation.from_rotvec([np.pi - 1e-9, 0.0, 0.0]).as_matrix()]
    mats = np.concatenate([mats, np.array(extra)])
    quat = quaternion_xyzw(mats)
    ref = Rotation.from_matrix(mats).as_quat()
    ref *= np.where(ref[:, 3:4] < 0, -1.0, 1.0)
    same = np.minimum(np.abs(quat - ref).max(axis=1), np.abs(quat + ref).max(axis=1))
    assert same.max() < 1e-12
    assert (quat[:, 3] >= 0).all()
    np.testing.assert_allclose(np.linalg.norm(quat, axis=1), 1.0, rtol=0, atol=1e-14)
    back = Rotation.from_quat(quat).as_matrix()
    np.testing.assert_allclose(back, mats, rtol=0, atol=1e-12)


def test_compiled_quaternions_are_the_numpy_ones_bit_for_bit():
    from scipy.spatial.transform import Rotation

    from athenakin import _dispatch
    from athenakin.ros._frames import _quaternion_xyzw_numpy, quaternion_xyzw

    R = Rotation.random(20000, random_state=2211).as_matrix()
    R[:10] = np.eye(3)                      # every branch of Shepperd's choice, ties,
    R[10:20] = np.diag([1.0, -1.0, -1.0])   # rounded entries, zeros, NaN
    R[20:30] = np.diag([-1.0, 1.0, -1.0])
    R[30:40] = np.diag([-1.0, -1.0, 1.0])
    R[40] = np.nan
    R[41, 0, 0] = np.nan
    R[42, 2, 2] = np.nan
    R[43] = -0.0
    R[44:2000] = np.round(R[44:2000], 1)
    if not _dispatch.numba_available():
        pytest.skip("numba not available here: the compiled quaternions need it")
    got, want = quaternion_xyzw(R), _quaternion_xyzw_numpy(R)
    assert np.array_equal(got, want, equal_nan=True)
    assert np.array_equal(np.signbit(got), np.signbit(want))

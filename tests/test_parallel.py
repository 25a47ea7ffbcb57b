"""The parallel module (Eq. 7-10): both assembly modes, tangency, IK."""

import numpy as np
import pytest

import athenakin as ak
from athenakin.errors import Reason
from athenakin.parallel import (
    circle_geometry,
    parallel_forward_kinematics,
    parallel_ik_from_position,
    parallel_inverse_kinematics,
)

SEED = 7
D = ak.Design.default()
FREE = ak.Design(l1=0.30, l2=0.10, l3=0.25, l4=0.15, l5=0.40)


def sample_q(rng, n, design=D):
    return rng.uniform(design.stroke_min, design.stroke_max, (n, 3))


def test_both_modes_lie_on_both_circles_and_frames_follow_model():
    rng = np.random.default_rng(SEED)
    q = sample_q(rng, 5000)
    par = parallel_forward_kinematics(q, D)
    g = circle_geometry(q, D)
    v = par.valid
    assert v.any()
    Oi = par.O_i
    xM = 0.5 * (q[:, 0] + q[:, 1])
    r1, my = g["r1"][:, None], g["m_y"][:, None]
    with np.errstate(invalid="ignore"):
        on_k1 = np.hypot(Oi[..., 1], Oi[..., 2]) - r1
        on_k2 = np.hypot(Oi[..., 1] - my, Oi[..., 2] - D.l5) - q[:, 2:3]
    assert np.abs(on_k1[v]).max() < 1e-14
    assert np.abs(on_k2[v]).max() < 1e-14
    assert np.abs(Oi[..., 0] - xM[:, None])[v].max() == 0
    # mode +1 has the larger z
    both = v.all(axis=1)
    assert np.all(Oi[both, 0, 2] >= Oi[both, 1, 2])
    # R_b_i = Rx(theta); z_i radial from M; O_s = O_i + l4 z_i; T_b_s has R_b_i
    R = par.T_b_i[..., :3, :3]
    th = par.theta
    Rx = np.zeros(R.shape)
    Rx[..., 0, 0] = 1
    Rx[..., 1, 1], Rx[..., 1, 2] = np.cos(th), -np.sin(th)
    Rx[..., 2, 1], Rx[..., 2, 2] = np.sin(th), np.cos(th)
    assert np.abs(R - Rx)[v].max() < 1e-14
    z_i = R[..., :, 2]
    radial = (Oi - np.stack([xM, 0 * xM, 0 * xM], -1)[:, None]) / r1[..., None]
    assert np.abs(z_i - radial)[v].max() < 1e-14
    assert np.abs(par.O_s - (Oi + D.l4 * z_i))[v].max() < 1e-15
    np.testing.assert_array_equal(par.T_b_s[..., :3, :3][v], R[v])
    # invalid slots are NaN, not garbage
    assert np.all(np.isnan(par.O_s[~v]))


def test_paper_w_and_half_chord_agree():
    """The stable factored w equals Eq. 8's w = -m_y^2 (d^2 - (r1+q3)^2)(d^2 - (r1-q3)^2)."""
    rng = np.random.default_rng(SEED + 1)
    q = sample_q(rng, 2000)
    g = circle_geometry(q, D)
    d2 = g["m_y"] ** 2 + D.l5**2
    w_paper = -g["m_y"] ** 2 * (d2 - (g["r1"] + q[:, 2]) ** 2) * (d2 - (g["r1"] - q[:, 2]) ** 2)
    np.testing.assert_allclose(g["w"], w_paper, rtol=1e-9, atol=1e-15)
    par = parallel_forward_kinematics(q, D)
    both = par.valid.all(axis=1)
    chord = np.linalg.norm(par.O_i[both, 0] - par.O_i[both, 1], axis=-1)
    np.testing.assert_allclose(chord, 2 * g["half_chord"][both], rtol=0, atol=1e-14)


def test_parallel_ik_round_trip_both_modes():
    rng = np.random.default_rng(SEED + 2)
    q = sample_q(rng, 5000)
    q = q[np.abs(q[:, 0] - q[:, 1]) > 0.02]
    par = parallel_forward_kinematics(q, D)
    for k, mode in enumerate((1, -1)):
        v = par.valid[:, k] & (par.half_chord > 1e-6)
        res = parallel_ik_from_position(par.O_s[v, k], D)
        assert res.valid.all()
        np.testing.assert_allclose(res.q, q[v], rtol=0, atol=1e-12)
        np.testing.assert_array_equal(res.mode, mode)
        res2 = parallel_inverse_kinematics(par.T_b_s[v, k], D)
        np.testing.assert_allclose(res2.q, q[v], rtol=0, atol=1e-12)
        np.testing.assert_allclose(res2.theta, par.theta[v, k], atol=1e-12)


def tangent_q(h=-0.1, x_M=0.0, outer=True):
    """Actuators at which k1 and k2 touch (w = 0)."""
    r1 = np.sqrt(D.l1**2 - h**2)
    my = np.sqrt(D.l3**2 - h**2) + D.l2
    d = np.hypot(my, D.l5)
    q3 = d + r1 if outer else d - r1
    return np.array([x_M + h, x_M - h, q3])


def test_tangent_circles_merge_modes():
    q = tangent_q(outer=False)
    par = parallel_forward_kinematics(q, D)
    assert par.valid[0] and not par.valid[1]
    assert par.reason[1] == Reason.CIRCLES_TANGENT
    assert par.half_chord <= ak.parallel.TANGENT_TOL


@pytest.mark.parametrize("delta", [1e-3, 1e-5, 1e-7, 1e-9, 1e-11])
def test_near_tangent_inside_and_outside(delta):
    q = tangent_q(outer=False)
    inside = parallel_forward_kinematics(q + [0, 0, delta], D)      # k2 grows: two points
    outside = parallel_forward_kinematics(q - [0, 0, delta], D)     # k2 shrinks: none
    a = inside.half_chord
    if a > ak.parallel.TANGENT_TOL:
        assert inside.valid.all()
        assert np.linalg.norm(inside.O_i[0] - inside.O_i[1]) > 0
    else:
        assert inside.reason[1] == Reason.CIRCLES_TANGENT
    # expected half-chord ~ sqrt(2 r1 q3 delta / d) to first order: check magnitude
    assert inside.half_chord > 0
    if outside.valid.any():  # within rounding of tangency: reported as tangent
        assert outside.reason[1] == Reason.CIRCLES_TANGENT
    else:
        assert np.all(outside.reason == Reason.CIRCLES_DISJOINT)


@pytest.mark.parametrize("q, reason", [
    ([0.0, 0.1, 0.05], Reason.CIRCLES_DISJOINT),      # k2 too small to reach k1
    ([-0.4, 0.3, 0.5], Reason.LINK_TOO_SHORT),        # |h| = 0.35 > l3
    ([0.1, -0.1, 0.45], Reason.AB_ORDER),             # q1 > q2 although design says q1 < q2
    ([np.nan, 0.1, 0.45], Reason.NONFINITE_INPUT),
])
def test_failure_reasons(q, reason):
    par = parallel_forward_kinematics(q, FREE)
    assert not par.valid.any()
    assert np.all(par.reason == reason)
    assert np.all(np.isnan(par.T_b_s))


def test_stroke_limit_reason_and_exact_limit_is_valid():
    q = np.array([D.q_min[0], 0.1, 0.45])
    assert parallel_forward_kinematics(q, D).valid[0]
    q2 = q - [1e-12, 0, 0]
    assert np.all(parallel_forward_kinematics(q2, D).reason == Reason.STROKE_LIMIT)


def test_ik_from_position_failures():
    res = parallel_ik_from_position([[0.0, 0.0, 0.1], [0.0, 0.0, 0.9], [0.0, 0.1, 0.3],
                                     [np.inf, 0, 0.3]], FREE)
    assert res.reason.tolist() == [Reason.NOT_IN_MODULE_IMAGE, Reason.LINK_TOO_SHORT, 0,
                                   Reason.NONFINITE_INPUT]
    assert np.all(np.isnan(res.q[[0, 1, 3]]))


def test_module_ik_rejects_pose_outside_its_image():
    par = parallel_forward_kinematics([-0.1, 0.1, 0.45], D)
    T = par.T_b_s[0].copy()
    c, s = np.cos(0.1), np.sin(0.1)
    T[:3, :3] = T[:3, :3] @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])  # rotated about z_s
    res = parallel_inverse_kinematics(T, D)
    assert not res.valid and res.reason == Reason.NOT_IN_MODULE_IMAGE


def test_batch_equals_loop():
    rng = np.random.default_rng(SEED + 3)
    q = sample_q(rng, 24).reshape(2, 3, 4, 3)
    par = parallel_forward_kinematics(q, D)
    assert par.T_b_s.shape == (2, 3, 4, 2, 4, 4)
    for idx in np.ndindex(2, 3, 4):
        one = parallel_forward_kinematics(q[idx], D)
        np.testing.assert_array_equal(one.valid, par.valid[idx])
        np.testing.assert_allclose(one.T_b_s, par.T_b_s[idx], atol=0, equal_nan=True)


def test_input_validation_messages():
    with pytest.raises(ak.InvalidInputError,
                       match="q: expected shape \\(\\.\\.\\., 3\\), got shape \\(2,\\)"):
        parallel_forward_kinematics([0.1, 0.2], D)
    with pytest.raises(TypeError, match="q: expected a real array"):
        parallel_forward_kinematics("0.1 0.2 0.3", D)


def test_circle_geometry_checks_its_arguments():
    """Audit of issue 13: circle_geometry validates q and design like the other functions."""
    D = ak.Design.default()
    with pytest.raises(TypeError, match="q"):
        circle_geometry(None, D)
    with pytest.raises(ak.InvalidInputError, match="q"):
        circle_geometry(np.zeros((2, 4)), D)
    with pytest.raises(TypeError, match="design"):
        circle_geometry([0.0, 0.0, 0.45], "default")
    g = circle_geometry([[np.nan, 0.0, 0.45]], D)         # NaN items stay NaN, no raise
    assert np.isnan(g["w"]).all()


def test_tolerance_and_error_arguments_named():
    D = ak.Design.default()
    sol = ak.parallel.parallel_forward_kinematics([-0.1, 0.1, 0.45], D)
    for tol in (None, float("nan"), -1.0):
        with pytest.raises((TypeError, ValueError), match="tol"):
            ak.parallel.parallel_inverse_kinematics(sol.T_b_s[0], D, tol=tol)
    with pytest.raises((TypeError, ValueError), match="dO"):
        ak.parallel.position_ik_error(sol.O_s[0], D, dO=10**400)

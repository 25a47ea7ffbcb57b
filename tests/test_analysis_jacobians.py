"""Analytic Jacobians against central finite differences of the core kinematics."""

import numpy as np
import pytest

import athenakin as ak
from athenakin.analysis import (
    instrument_inverse_jacobian,
    instrument_jacobian,
    parallel_inverse_jacobian,
    parallel_jacobian,
    parallel_state,
    parallel_twist_jacobian,
    passive_jacobian,
    serial_jacobian,
    tool_tip_inverse_jacobian,
    tool_tip_jacobian,
)
from athenakin.chain import ups_transform
from athenakin.testing import random_configurations

SEED = 20240611
N = 1200
EPS = 1e-7          # central-difference step (m, rad)
FD_RTOL = 1e-6      # |J - J_fd| <= FD_RTOL * max(1, max|J|) per configuration
DESIGN = ak.Design.default()


@pytest.fixture(scope="module")
def rc():
    return random_configurations(N, DESIGN, rng=SEED)


def _fd(f, x, n_out, *, eps=EPS, wrap_rows=()):
    cols = []
    for i in range(x.shape[-1]):
        e = np.zeros(x.shape[-1])
        e[i] = eps
        d = f(x + e) - f(x - e)
        for r in wrap_rows:
            d[..., r] = np.angle(np.exp(1j * d[..., r]))
        cols.append(d / (2 * eps))
    return np.stack(cols, axis=-1)


def _assert_fd(J, Jfd):
    assert J.shape == Jfd.shape
    scale = np.maximum(1.0, np.abs(J).max(axis=(-2, -1)))
    err = np.abs(J - Jfd).max(axis=(-2, -1)) / scale
    assert np.all(np.isfinite(err))
    worst = int(np.argmax(err))
    assert err.max() <= FD_RTOL, f"worst item {worst}: relative error {err.max():.2e}"


def _O_s(q, mode):
    par = ak.parallel.parallel_forward_kinematics(q, DESIGN)
    return np.where((mode == 1)[:, None], par.O_s[:, 0], par.O_s[:, 1])


def _T_b_s(q, mode):
    par = ak.parallel.parallel_forward_kinematics(q, DESIGN)
    return np.where((mode == 1)[:, None, None], par.T_b_s[:, 0], par.T_b_s[:, 1])


def _twist_fd(f, x):
    """(v, omega) finite differences of a pose-valued function, base frame."""
    cols = []
    for i in range(x.shape[-1]):
        e = np.zeros(x.shape[-1])
        e[i] = EPS
        dT = (f(x + e) - f(x - e)) / (2 * EPS)
        T = f(x)
        W = dT[..., :3, :3] @ np.swapaxes(T[..., :3, :3], -1, -2)
        w = np.stack([W[..., 2, 1], W[..., 0, 2], W[..., 1, 0]], axis=-1)
        cols.append(np.concatenate([dT[..., :3, 3], w], axis=-1))
    return np.stack(cols, axis=-1)


def test_parallel_jacobian_matches_finite_differences(rc):
    J = parallel_jacobian(rc.q, DESIGN, mode=rc.mode)
    assert J.shape == (N, 3, 3)
    _assert_fd(J, _fd(lambda q: _O_s(q, rc.mode), rc.q, 3))


def test_parallel_state_puts_O_s_where_the_core_does(rc):
    g = parallel_state(rc.q, DESIGN, rc.mode)
    np.testing.assert_allclose(g["O_s"], _O_s(rc.q, rc.mode), rtol=0, atol=1e-12)


def test_parallel_inverse_jacobian_is_the_inverse_and_matches_ik(rc):
    J = parallel_jacobian(rc.q, DESIGN, mode=rc.mode)
    Ji = parallel_inverse_jacobian(rc.q, DESIGN, mode=rc.mode)
    np.testing.assert_allclose(Ji @ J, np.broadcast_to(np.eye(3), J.shape), rtol=0, atol=1e-9)
    O_b = _O_s(rc.q, rc.mode)

    def ik(P):
        return ak.parallel.parallel_ik_from_position(P, DESIGN).q

    _assert_fd(Ji, _fd(ik, O_b, 3))


def test_parallel_twist_jacobian_matches_finite_differences(rc):
    Jt = parallel_twist_jacobian(rc.q, DESIGN, mode=rc.mode)
    assert Jt.shape == (N, 6, 3)
    np.testing.assert_array_equal(Jt[:, 4:, :], 0.0)  # R_b_s = Rx(theta)
    _assert_fd(Jt, _twist_fd(lambda q: _T_b_s(q, rc.mode), rc.q))


def test_parallel_jacobian_closed_form_determinant(rc):
    g = parallel_state(rc.q, DESIGN, rc.mode)
    det = g["mode"] * (g["r1"] + DESIGN.l4) * g["h"] * g["q3"] / (2 * g["r1"] * g["a"] * g["d"])
    np.testing.assert_allclose(np.linalg.det(parallel_jacobian(rc.q, DESIGN, rc.mode)), det,
                               rtol=1e-10)


def _chain(x):
    return ups_transform(x[..., 2], np.concatenate([x[..., :2], x[..., 3:]], axis=-1))


def test_serial_jacobian_matches_finite_differences_in_both_frames(rc):
    x = np.concatenate([rc.u[:, :2], rc.p[:, None], rc.u[:, 2:]], axis=-1)
    Js = serial_jacobian(rc.p, rc.u, frame="s")
    assert Js.shape == (N, 6, 6)
    _assert_fd(Js, _twist_fd(_chain, x))
    Je = serial_jacobian(rc.p, rc.u, frame="e")
    Rt = np.swapaxes(_chain(x)[:, :3, :3], -1, -2)
    np.testing.assert_allclose(Je[:, :3], Rt @ Js[:, :3], rtol=0, atol=1e-12)
    np.testing.assert_allclose(Je[:, 3:], Rt @ Js[:, 3:], rtol=0, atol=1e-12)


def test_serial_jacobian_determinant_is_p2_sin_u2_sin_u4(rc):
    det = np.linalg.det(serial_jacobian(rc.p, rc.u))
    np.testing.assert_allclose(det, rc.p ** 2 * np.sin(rc.u[:, 1]) * np.sin(rc.u[:, 3]),
                               rtol=1e-9, atol=1e-15)


def test_passive_jacobian_matches_finite_differences_of_fk(rc):
    Jp = passive_jacobian(rc.q, rc.p, rc.u, DESIGN, mode=rc.mode)
    assert Jp.shape == (N, 6, 3)
    idx = np.arange(N)

    def passive(q):
        sol = ak.forward_kinematics(q, rc.T_b_e, DESIGN, errors="flag")
        p, u = sol.p[idx, rc.slot], sol.u[idx, rc.slot]
        return np.concatenate([u[:, :2], p[:, None], u[:, 2:]], axis=-1)

    np.testing.assert_allclose(np.angle(np.exp(1j * (passive(rc.q)[:, [0, 1, 3, 4, 5]]
                                                     - rc.u))), 0, atol=1e-9)
    _assert_fd(Jp, _fd(passive, rc.q, 6, wrap_rows=(0, 1, 3, 4, 5)))


def _instrument(q, mode, T, frame):
    O_b = _O_s(q, mode)
    r = T[:, :3, 3] - O_b
    p = np.linalg.norm(r, axis=-1)
    d_b = r / p[:, None]
    d_f = d_b if frame == "base" else np.einsum("nji,nj->ni", T[:, :3, :3], d_b)
    az, pol = ak.angles_from_direction(d_f)
    return np.stack([az, pol, p], axis=-1)


def _tip(q, mode, T, frame):
    O_b = _O_s(q, mode)
    r = T[:, :3, 3] - O_b
    t = O_b + DESIGN.tool_length * r / np.linalg.norm(r, axis=-1)[:, None]
    return t if frame == "base" else np.einsum("nji,nj->ni", T[:, :3, :3], t - T[:, :3, 3])


@pytest.mark.parametrize("frame", ["rcm", "base"])
def test_instrument_jacobian_matches_finite_differences(rc, frame):
    J = instrument_jacobian(rc.q, rc.T_b_e, DESIGN, mode=rc.mode, frame=frame)
    _assert_fd(J, _fd(lambda q: _instrument(q, rc.mode, rc.T_b_e, frame), rc.q, 3,
                      wrap_rows=(0,)))
    Ji = instrument_inverse_jacobian(rc.q, rc.T_b_e, DESIGN, mode=rc.mode, frame=frame)
    np.testing.assert_allclose(Ji @ J, np.broadcast_to(np.eye(3), J.shape), rtol=0, atol=1e-9)


def test_instrument_inverse_jacobian_matches_q_from_instrument(rc):
    Ji = instrument_inverse_jacobian(rc.q, rc.T_b_e, DESIGN, mode=rc.mode, frame="rcm")
    x0 = _instrument(rc.q, rc.mode, rc.T_b_e, "rcm")

    def q_of(x):
        q, _ = ak.q_from_instrument(rc.T_b_e, ak.direction_from_angles(x[:, 0], x[:, 1]),
                                    x[:, 2], DESIGN, errors="flag")
        return q

    _assert_fd(Ji, _fd(q_of, x0, 3))


@pytest.mark.parametrize("frame", ["base", "rcm"])
def test_tool_tip_jacobian_matches_finite_differences(rc, frame):
    J = tool_tip_jacobian(rc.q, rc.T_b_e, DESIGN, mode=rc.mode, frame=frame)
    _assert_fd(J, _fd(lambda q: _tip(q, rc.mode, rc.T_b_e, frame), rc.q, 3))
    Ji = tool_tip_inverse_jacobian(rc.q, rc.T_b_e, DESIGN, mode=rc.mode, frame=frame)
    # away from p = L, where N^-1 is unbounded
    ok = np.abs(np.linalg.norm(rc.T_b_e[:, :3, 3] - _O_s(rc.q, rc.mode), axis=-1)
                - DESIGN.tool_length) > 0.02
    np.testing.assert_allclose((Ji @ J)[ok], np.broadcast_to(np.eye(3), J[ok].shape), rtol=0,
                               atol=1e-8)


def test_tool_tip_inverse_jacobian_matches_q_from_tool_tip(rc):
    O_b = _O_s(rc.q, rc.mode)
    p = np.linalg.norm(rc.T_b_e[:, :3, 3] - O_b, axis=-1)
    ok = p < DESIGN.tool_length - 0.05  # the tip beyond the RCM, away from p = L
    T, q, m = rc.T_b_e[ok], rc.q[ok], rc.mode[ok]
    Ji = tool_tip_inverse_jacobian(q, T, DESIGN, mode=m, frame="rcm")
    tip0 = _tip(q, m, T, "rcm")

    def q_of(t):
        qq, _ = ak.q_from_tool_tip(T, t, DESIGN, errors="flag")
        return qq

    assert ok.sum() > 500
    _assert_fd(Ji, _fd(q_of, tip0, 3))


def test_whole_robot_determinants(rc):
    """det J_tip = (1 - L/p)^2 det J_par; |det J_angles| = |det J_par| / (p^2 sin polar)."""
    Jp = parallel_jacobian(rc.q, DESIGN, mode=rc.mode)
    x = _instrument(rc.q, rc.mode, rc.T_b_e, "rcm")
    p, pol = x[:, 2], x[:, 1]
    L = DESIGN.tool_length
    np.testing.assert_allclose(
        np.linalg.det(tool_tip_jacobian(rc.q, rc.T_b_e, DESIGN, mode=rc.mode)),
        (1 - L / p) ** 2 * np.linalg.det(Jp), rtol=1e-8, atol=1e-14)
    np.testing.assert_allclose(
        np.abs(np.linalg.det(instrument_jacobian(rc.q, rc.T_b_e, DESIGN, mode=rc.mode))),
        np.abs(np.linalg.det(Jp)) / (p ** 2 * np.sin(pol)), rtol=1e-8)


def test_batch_equals_loop(rc):
    q, m, T = rc.q[:20].reshape(4, 5, 3), rc.mode[:20].reshape(4, 5), rc.T_b_e[:20]
    T = T.reshape(4, 5, 4, 4)
    for fn in (tool_tip_jacobian, instrument_jacobian, instrument_inverse_jacobian):
        Jb = fn(q, T, DESIGN, mode=m)
        assert Jb.shape == (4, 5, 3, 3)
        for i in range(4):
            for j in range(5):
                np.testing.assert_allclose(Jb[i, j], fn(q[i, j], T[i, j], DESIGN, mode=m[i, j]),
                                           rtol=0, atol=1e-13)
    Jb = parallel_jacobian(q, DESIGN, m)
    assert parallel_jacobian(q[0, 0], DESIGN, 1).shape == (3, 3)
    np.testing.assert_allclose(Jb[1, 2], parallel_jacobian(q[1, 2], DESIGN, m[1, 2]), atol=0)


def test_default_arguments_and_modes_differ():
    q = ak.robot.REFERENCE_Q
    J = parallel_jacobian(q)
    np.testing.assert_array_equal(J, parallel_jacobian(q, DESIGN, mode=1))
    assert not np.allclose(J, parallel_jacobian(q, DESIGN, mode=-1))
    np.testing.assert_array_equal(tool_tip_jacobian(q),
                                  tool_tip_jacobian(q, ak.default_rcm_frame(DESIGN), DESIGN))


def test_not_assembled_gives_nan():
    J = parallel_jacobian([-0.1, 0.1, 0.05], DESIGN)  # k2 too small to reach k1
    assert np.all(np.isnan(J[1:]))


@pytest.mark.parametrize("bad, match", [
    ({"mode": 0}, "mode: expected"),
    ({"mode": 2}, "mode: expected"),
])
def test_mode_is_validated(bad, match):
    with pytest.raises(ak.InvalidInputError, match=match):
        parallel_jacobian([-0.1, 0.1, 0.45], DESIGN, **bad)


def test_frame_and_shapes_are_validated():
    with pytest.raises(ak.InvalidInputError, match="frame: expected"):
        tool_tip_jacobian([-0.1, 0.1, 0.45], frame="tool")
    with pytest.raises(ak.InvalidInputError, match="frame: expected"):
        serial_jacobian(0.2, np.zeros(5), frame="base")
    with pytest.raises(ak.InvalidInputError, match=r"q: expected shape \(\.\.\., 3\)"):
        parallel_jacobian([0.1, 0.2])
    with pytest.raises(TypeError, match="design: expected athenakin.Design"):
        parallel_jacobian([-0.1, 0.1, 0.45], "default")

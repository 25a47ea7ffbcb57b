"""The serial UPS chain: forward map and its 8 solutions, degenerate cases."""

import numpy as np
import pytest

from athenakin.chain import (
    SERIAL_P_SIGN,
    SERIAL_UJOINT,
    SERIAL_WRIST,
    ups_solutions,
    ups_transform,
)
from athenakin.errors import Reason
from athenakin.testing import assert_angles_equal

SEED = 11


def chain_product(p, u):
    """Eq. 11 typed as a product of 4x4 matrices (docs/conventions.md), for one configuration."""
    def rz(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    P = np.array([[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1.0]])
    Tz = np.eye(4)
    Tz[2, 3] = p
    return rz(u[0]) @ P @ rz(u[1]) @ P @ Tz @ rz(u[2]) @ P @ rz(u[3]) @ P @ rz(u[4])


def test_closed_form_equals_matrix_product():
    rng = np.random.default_rng(SEED)
    p = rng.uniform(-1, 1, 300)
    u = rng.uniform(-np.pi, np.pi, (300, 5))
    T = ups_transform(p, u)
    for i in range(300):
        np.testing.assert_allclose(T[i], chain_product(p[i], u[i]), rtol=0, atol=1e-15)


def random_generic(rng, n, margin=0.05):
    p = rng.uniform(0.02, 1, n) * rng.choice([-1, 1], n)
    u = rng.uniform(-np.pi, np.pi, (n, 5))
    keep = (np.abs(np.sin(u[:, 1])) > margin) & (np.abs(np.sin(u[:, 3])) > margin)
    return p[keep], u[keep]


def test_eight_distinct_solutions_contain_the_original():
    rng = np.random.default_rng(SEED + 1)
    p, u = random_generic(rng, 20000)
    sol = ups_solutions(ups_transform(p, u))
    assert sol.valid.all()
    assert np.nanmax(sol.residual) < 1e-13
    # labels: sign of p, sin u2, sin u4
    np.testing.assert_array_equal(np.sign(sol.p), np.broadcast_to(SERIAL_P_SIGN, sol.p.shape))
    np.testing.assert_array_equal(np.sign(np.sin(sol.u[..., 1])),
                                  np.broadcast_to(SERIAL_UJOINT, sol.p.shape))
    np.testing.assert_array_equal(np.sign(np.sin(sol.u[..., 3])),
                                  np.broadcast_to(SERIAL_WRIST, sol.p.shape))
    k = 4 * (p < 0) + 2 * (np.sin(u[:, 1]) < 0) + (np.sin(u[:, 3]) < 0)
    i = np.arange(len(p))
    np.testing.assert_allclose(sol.p[i, k], p, rtol=0, atol=1e-14)
    assert_angles_equal(sol.u[i, k], u, atol=1e-12)
    # the 8 are pairwise distinct (no two coincide: branches differ by half turns)
    diff = np.abs(np.angle(np.exp(1j * (sol.u[:, :, None] - sol.u[:, None, :])))).max(-1)
    diff = diff + np.abs(sol.p[:, :, None] - sol.p[:, None, :])
    off = ~np.eye(8, dtype=bool)
    assert diff[:, off].min() > 0.05
    assert np.all(np.abs(sol.u) <= np.pi)
    assert np.all(sol.u > -np.pi)


def test_branch_relations():
    """U-joint branches (u1, u2) ~ (u1 + pi, -u2); wrist (u3, u4, u5) ~ (u3 + pi, -u4, u5 + pi)."""
    rng = np.random.default_rng(SEED + 2)
    p, u = random_generic(rng, 500)
    sol = ups_solutions(ups_transform(p, u))
    U = sol.u
    assert_angles_equal(U[:, 2, 0], U[:, 0, 0] + np.pi)
    assert_angles_equal(U[:, 2, 1], -U[:, 0, 1])
    assert_angles_equal(U[:, 1, 2], U[:, 0, 2] + np.pi)
    assert_angles_equal(U[:, 1, 3], -U[:, 0, 3])
    assert_angles_equal(U[:, 1, 4], U[:, 0, 4] + np.pi)
    np.testing.assert_allclose(sol.p[:, 4], -sol.p[:, 0], atol=0)


@pytest.mark.parametrize("which, reason", [
    ("p", Reason.SERIAL_P_ZERO), ("u2", Reason.UJOINT_SINGULAR), ("u4", Reason.WRIST_SINGULAR)])
def test_exact_degenerate_cases_are_reported_not_returned(which, reason):
    u = np.array([0.3, 0.7, -0.4, 1.1, 0.2])
    p = 0.3
    if which == "p":
        p = 0.0
    elif which == "u2":
        u[1] = 0.0
    else:
        u[3] = np.pi
    sol = ups_solutions(ups_transform(p, u))
    if which == "u4":
        # the wrist degenerates in every slot (same z3 for all, u4 = 0 or pi)
        assert np.all(sol.reason == reason)
    else:
        assert np.all(sol.reason == reason)
    assert not sol.valid.any()
    assert np.all(np.isnan(sol.u)) and np.all(np.isnan(sol.p))


@pytest.mark.parametrize("eps", [1e-3, 1e-6, 1e-9, 1e-11])
@pytest.mark.parametrize("which", ["u2", "u4"])
def test_near_degenerate_solutions_still_close(eps, which):
    u = np.array([0.3, 0.7, -0.4, 1.1, 0.2])
    u[1 if which == "u2" else 3] = eps
    T = ups_transform(0.25, u)
    sol = ups_solutions(T)
    assert sol.valid.all()
    # closure holds to rounding; angles of the near-free pair are ill-conditioned ~ eps_mach / eps
    assert np.nanmax(sol.residual) < 1e-12
    k = 0
    np.testing.assert_allclose(sol.p[k], 0.25, atol=1e-15)
    assert abs(np.sin(sol.u[k, 1 if which == "u2" else 3])) == pytest.approx(np.sin(eps),
                                                                             rel=1e-3)


def test_p_near_zero():
    u = np.array([0.3, 0.7, -0.4, 1.1, 0.2])
    for p in [1e-3, 1e-6, 1e-9]:
        sol = ups_solutions(ups_transform(p, u))
        assert sol.valid.all() and np.nanmax(sol.residual) < 1e-12
    sol = ups_solutions(ups_transform(1e-13, u))
    assert np.all(sol.reason == Reason.SERIAL_P_ZERO)


def test_nonfinite_pose_flagged_in_batch():
    T = np.stack([ups_transform(0.3, np.zeros(5) + 0.4), np.full((4, 4), np.nan)])
    sol = ups_solutions(T)
    assert sol.valid[0].all()
    assert np.all(sol.reason[1] == Reason.NONFINITE_INPUT)


def test_scale_and_tolerances_named():
    """Audit of issue 13: a 400-digit scale is a named error, not an OverflowError."""
    T = ups_transform(0.2, np.array([0.3, 0.5, 0.2, 0.4, 0.1]))
    with pytest.raises((TypeError, ValueError), match="scale"):
        ups_solutions(T, scale=10**400)
    with pytest.raises(ValueError, match="closure_tol"):
        ups_solutions(T, closure_tol=float("nan"))


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize("p", [1e8, 1e150, 1e200, 1e300])
def test_huge_translation_valid_is_finite(p):
    """Audit of issue 13: |t| = 1e300 overflowed |t|^2 and gave valid slots with p = inf;
    a far pose closes to its own rounding (eps |t|), and is valid while |t|^2 is finite."""
    T = ups_transform(p, np.array([0.3, 0.5, 0.2, 0.4, 0.1]))
    sol = ups_solutions(T)
    assert np.all(np.isfinite(sol.p[sol.valid]))
    assert sol.valid.any() == (p < 1e154)


def test_scale_must_broadcast_to_the_batch():
    T = ups_transform(0.2, np.array([0.3, 0.5, 0.2, 0.4, 0.1]))
    with pytest.raises(ValueError, match="scale"):
        ups_solutions(T, scale=[])

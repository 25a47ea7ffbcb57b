"""Certified forward kinematics (athenakin.certified): enclosures, proofs of count, refusals."""

import numpy as np
import pytest

import athenakin as ak
from athenakin.certified import CertStatus, certified_forward_kinematics
from athenakin.chain import ups_transform
from athenakin.errors import InvalidInputError, Reason
from athenakin.testing import random_configurations

pytest.importorskip("flint")

D = ak.Design.default()
D_FREE = ak.Design(l1=0.30, l2=0.10, l3=0.25, l4=0.15, l5=0.40)   # no stroke limits
T_REF = ak.default_rcm_frame(D)
Q_REF = np.array([-0.10, 0.10, 0.45])

# A design with dyadic lengths: at q = (0, 0, 0.625) mode +1 puts O_i exactly above M
# (theta = 0, R_b_s = I, O_s = (0, 0, 0.5)), so set-ups built from joint angles that are
# multiples of pi/2 are exact in binary and sit exactly on a singular set.
D_DYADIC = ak.Design(l1=0.375, l2=0.125, l3=0.25, l4=0.125, l5=0.875, tool_length=0.5)
Q_DYADIC = np.array([0.0, 0.0, 0.625])
# with l5 = 0.5, |C| = 0.625 = r1 + 0.25: q3 = 0.25 makes k1 and k2 exactly tangent
D_TANGENT = ak.Design(l1=0.375, l2=0.125, l3=0.25, l4=0.125, l5=0.5, tool_length=0.5)


def tip_float(sol, T_b_e, L):
    """Tool tips of FK slots, base frame: O_s + L (t_e - O_s) / p."""
    O_s = sol.T_b_s[..., :3, 3]
    t_e = np.asarray(T_b_e)[..., None, :3, 3]
    return O_s + L * (t_e - O_s) / sol.p[..., None]


def exact_set_up(u, p):
    """T_b_e for the dyadic design at Q_DYADIC, angles multiples of pi/2 (exact entries)."""
    T = ups_transform(p, np.asarray(u, float))
    T[:3, :3] = np.round(T[:3, :3])          # cos(pi/2) = 6e-17 in floats: make it exact
    T[:3, 3] = np.round(T[:3, 3] / p) * p if p != 0 else 0.0
    T[2, 3] += 0.5                            # T_b_s = translation (0, 0, 0.5)
    return T


def in_box(lo, hi, x):
    return np.all((lo <= x) & (x <= hi), axis=-1)


# ------------------------------------------------------------------------- generic poses
def test_reference_configuration_all_16_certified_and_tight():
    cert = certified_forward_kinematics(Q_REF, T_REF, D)
    assert cert.certified.shape == (16,) and bool(cert.complete)
    assert int(cert.n_certified) == 16
    assert np.all(cert.status == CertStatus.CERTIFIED) and np.all(cert.reason == 0)
    widths = np.r_[cert.p_hi - cert.p_lo, (cert.u_hi - cert.u_lo).ravel(),
                   (cert.O_s_hi - cert.O_s_lo).ravel(), (cert.tip_hi - cert.tip_lo).ravel()]
    assert np.all(widths > 0) and widths.max() <= 1e-12


def test_seeded_poses_boxes_contain_both_float_solvers():
    """1,000 seeded generic poses: certified set = FK's valid set, both solvers inside."""
    cfg = random_configurations(1000, D, rng=20261123)
    cert = certified_forward_kinematics(cfg.q, cfg.T_b_e, D)
    closed = ak.forward_kinematics(cfg.q, cfg.T_b_e, D)
    algebraic = ak.forward_kinematics(cfg.q, cfg.T_b_e, D, method="algebraic")
    assert np.array_equal(cert.certified, closed.valid)
    assert np.all(cert.complete)
    assert np.all(cert.contains(closed.p, closed.u) == closed.valid)
    both = closed.valid & algebraic.valid
    assert np.all(cert.contains(algebraic.p, algebraic.u)[both])
    v = closed.valid
    assert np.all(in_box(cert.O_s_lo, cert.O_s_hi, closed.T_b_s[..., :3, 3])[v])
    assert np.all(in_box(cert.tip_lo, cert.tip_hi, tip_float(closed, cfg.T_b_e, D.tool_length))[v])
    # the slot that generated each pose is certified and contains the generating (p, u)
    k = cfg.slot
    rows = np.arange(len(k))
    assert np.all(cert.certified[rows, k])
    assert np.all((cert.p_lo[rows, k] <= cfg.p) & (cfg.p <= cert.p_hi[rows, k]))
    widths = np.r_[(cert.p_hi - cert.p_lo)[v], (cert.u_hi - cert.u_lo)[v].ravel()]
    assert np.median(widths) < 1e-13 and np.percentile(widths, 99) <= 1e-12


@pytest.mark.parametrize("margin", [1e-4, 1e-7])
def test_near_singular_poses_boxes_still_contain_the_closed_form(margin):
    """Poses close to every singular set: wider boxes, still containing the float FK."""
    cfg = random_configurations(200, D, rng=7, margin=margin, length_margin=margin)
    cert = certified_forward_kinematics(cfg.q, cfg.T_b_e, D)
    closed = ak.forward_kinematics(cfg.q, cfg.T_b_e, D)
    both = cert.certified & closed.valid
    assert both.sum() > 0.9 * cert.certified.sum() > 0
    assert np.all(cert.contains(closed.p, closed.u)[both])


def test_exact_input_gives_tighter_boxes_and_contains_the_generating_solution():
    cfg = random_configurations(20, D, rng=3)
    wide = certified_forward_kinematics(cfg.q, cfg.T_b_e, D)
    exact = certified_forward_kinematics(cfg.q, cfg.T_b_e, D, input_tol=0.0)
    assert np.array_equal(wide.certified, exact.certified)
    c = exact.certified
    assert np.all((exact.p_hi - exact.p_lo)[c] <= (wide.p_hi - wide.p_lo)[c])
    # nested: the exact-input enclosure lies in the input-ball enclosure
    assert np.all((wide.p_lo <= exact.p_lo)[c] & (exact.p_hi <= wide.p_hi)[c])


def test_precision_is_raised_when_a_proof_fails_for_lack_of_it():
    """1e-9 from u2 = 0, 16 bits cannot tell sin u2 from 0: the precision is doubled."""
    T = ups_transform(0.25, np.array([1.0, 1e-9, 2.0, 1.0, 0.5]))
    T[2, 3] += 0.5                            # T_b_s = translation (0, 0, 0.5)
    cert = certified_forward_kinematics(Q_DYADIC, T, D_DYADIC, input_tol=0.0, prec=16)
    assert int(cert.prec) > 16 and bool(cert.complete) and int(cert.n_certified) == 16
    low = certified_forward_kinematics(Q_DYADIC, T, D_DYADIC, input_tol=0.0, prec=16,
                                       max_prec=16)
    assert not np.any(low.certified[:8]) and np.all(low.reason[:8] == Reason.UJOINT_SINGULAR)


def test_batch_broadcasts_and_equals_the_loop():
    q = np.array([Q_REF, Q_REF + [0.01, -0.01, 0.0], Q_REF + [0.0, 0.0, 0.02]])
    batch = certified_forward_kinematics(q, T_REF, D)
    assert batch.p_lo.shape == (3, 16) and batch.u_lo.shape == (3, 16, 5)
    for i in range(3):
        one = certified_forward_kinematics(q[i], T_REF, D)
        np.testing.assert_array_equal(batch.p_lo[i], one.p_lo)
        np.testing.assert_array_equal(batch.u_hi[i], one.u_hi)
        np.testing.assert_array_equal(batch.status[i], one.status)


# ---------------------------------------------------------- exact singular configurations
def test_dyadic_set_up_is_exact_and_regular():
    """The construction itself: a regular exact set-up is fully certified."""
    T = exact_set_up([np.pi / 2, np.pi / 2, np.pi / 2, np.pi / 2, 0.0], 0.25)
    cert = certified_forward_kinematics(Q_DYADIC, T, D_DYADIC, input_tol=0.0)
    assert bool(cert.complete) and int(cert.n_certified) == 16
    # mode +1 has O_s exactly at (0, 0, 0.5): the boxes hold it and are a few ulps wide
    assert np.all(in_box(cert.O_s_lo[:8], cert.O_s_hi[:8], [0.0, 0.0, 0.5]))
    assert np.all(cert.O_s_hi - cert.O_s_lo <= 1e-14)


@pytest.mark.parametrize("input_tol", [0.0, 2.0 ** -50])
@pytest.mark.parametrize("name, u, p, reason", [
    ("u2 = 0", [np.pi / 2, 0.0, np.pi / 2, np.pi / 2, 0.0], 0.25, Reason.UJOINT_SINGULAR),
    ("u4 = 0", [np.pi / 2, np.pi / 2, np.pi / 2, 0.0, 0.0], 0.25, Reason.WRIST_SINGULAR),
    ("p = 0", [np.pi / 2, np.pi / 2, np.pi / 2, np.pi / 2, 0.0], 0.0, Reason.SERIAL_P_ZERO),
])
def test_exact_serial_singularities_certify_no_slot_of_that_mode(name, u, p, reason, input_tol):
    T = exact_set_up(u, p)
    cert = certified_forward_kinematics(Q_DYADIC, T, D_DYADIC, input_tol=input_tol,
                                        max_prec=256)
    mode1 = slice(0, 8)
    assert not np.any(cert.certified[mode1]), name
    assert np.all(cert.status[mode1] == CertStatus.UNDECIDED)
    assert np.all(cert.reason[mode1] == reason)
    assert not bool(cert.complete)
    assert np.all(np.isnan(cert.p_lo[mode1]))


@pytest.mark.parametrize("input_tol", [0.0, 2.0 ** -50])
def test_exact_tangency_certifies_nothing(input_tol):
    T = exact_set_up([np.pi / 2, np.pi / 2, np.pi / 2, np.pi / 2, 0.0], 0.25)
    cert = certified_forward_kinematics([0.0, 0.0, 0.25], T, D_TANGENT, input_tol=input_tol,
                                        max_prec=256)
    assert not np.any(cert.certified)
    assert np.all(cert.reason == Reason.CIRCLES_TANGENT) and not bool(cert.complete)


# ------------------------------------------------------------------ proven absence
@pytest.mark.parametrize("q, design, reason", [
    ([-0.10, 0.10, 2.0], D_FREE, Reason.CIRCLES_DISJOINT),
    ([-0.40, 0.40, 0.45], D_FREE, Reason.LINK_TOO_SHORT),
    ([-0.40, 0.40, 0.45], ak.Design(l1=0.30, l2=0.10, l3=0.5, l4=0.15, l5=0.40),
     Reason.LINK_TOO_SHORT),
    ([0.10, -0.10, 0.45], D, Reason.AB_ORDER),
    ([-0.10, 0.10, 0.45], ak.Design(l1=0.30, l2=0.10, l3=0.25, l4=0.15, l5=0.40,
                                    q_min=(-0.5, -0.5, 0.5), q_max=(0.5, 0.5, 0.9)),
     Reason.STROKE_LIMIT),
])
def test_unreachable_input_is_certified_to_have_no_solution(q, design, reason):
    cert = certified_forward_kinematics(q, T_REF, design)
    assert bool(cert.complete) and int(cert.n_certified) == 0
    assert np.all(cert.status == CertStatus.ABSENT) and np.all(cert.reason == reason)
    fk = ak.forward_kinematics(q, T_REF, design, errors="flag")
    assert not np.any(fk.valid)


# ---------------------------------------------------------------- the certificate does not lie
def test_wrong_solutions_are_not_contained():
    cert = certified_forward_kinematics(Q_REF, T_REF, D)
    sol = ak.forward_kinematics(Q_REF, T_REF, D)
    assert np.all(cert.contains(sol.p, sol.u))
    assert not np.any(cert.contains(sol.p + 1e-11, sol.u))
    du = np.zeros(5)
    du[4] = 1e-11
    assert not np.any(cert.contains(sol.p, sol.u + du))
    # a slot's solution is not accepted in another slot
    assert not np.any(cert.contains(sol.p[::-1], sol.u[::-1]))
    # the same angles modulo 2 pi are
    assert np.all(cert.contains(sol.p, sol.u + 2 * np.pi))


def test_inconsistent_input_is_not_vouched_for():
    """Solutions of a slightly different input lie outside the boxes of this one."""
    cert = certified_forward_kinematics(Q_REF, T_REF, D)
    for dq in ([1e-9, 0, 0], [0, 0, 1e-9]):
        other = ak.forward_kinematics(Q_REF + np.array(dq), T_REF, D)
        assert not np.any(cert.contains(other.p, other.u))
    T = T_REF.copy()
    T[0, 3] += 1e-9
    other = ak.forward_kinematics(Q_REF, T, D)
    assert not np.any(cert.contains(other.p, other.u))


# ---------------------------------------------------------------------------- bad input
def test_nan_single_item_raises_and_batch_flags():
    with pytest.raises(InvalidInputError, match="q"):
        certified_forward_kinematics([np.nan, 0.1, 0.45], T_REF, D)
    cert = certified_forward_kinematics([[np.nan, 0.1, 0.45], Q_REF], T_REF, D)
    assert np.all(cert.status[0] == CertStatus.NONFINITE_INPUT)
    assert np.all(cert.reason[0] == Reason.NONFINITE_INPUT) and not cert.complete[0]
    assert int(cert.n_certified[1]) == 16


@pytest.mark.parametrize("kwargs, exc, match", [
    ({"input_tol": -1.0}, InvalidInputError, "input_tol"),
    ({"input_tol": float("nan")}, InvalidInputError, "input_tol"),
    ({"input_tol": "1e-15"}, TypeError, "input_tol"),
    ({"prec": 8}, InvalidInputError, "prec"),
    ({"prec": 256, "max_prec": 128}, InvalidInputError, "max_prec"),
    ({"prec": 64.0}, TypeError, "prec"),
])
def test_bad_options_are_named(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        certified_forward_kinematics(Q_REF, T_REF, D, **kwargs)


def test_bad_shapes_and_non_rigid_frame_are_named():
    with pytest.raises(InvalidInputError, match="q"):
        certified_forward_kinematics([0.1, 0.2], T_REF, D)
    with pytest.raises(InvalidInputError, match="T_b_e"):
        certified_forward_kinematics(Q_REF, np.eye(3), D)
    skew = T_REF.copy()
    skew[0, 0] += 1e-3
    with pytest.raises(InvalidInputError, match="T_b_e"):
        certified_forward_kinematics(Q_REF, skew, D)
    with pytest.raises(InvalidInputError, match="broadcast"):
        certified_forward_kinematics(np.tile(Q_REF, (3, 1)), np.tile(T_REF, (2, 1, 1)), D)


# ------------------------------------------------------------------------- packaging
def test_docstring_example_runs():
    import doctest

    import athenakin.certified._fk as mod

    assert doctest.testmod(mod, optionflags=doctest.ELLIPSIS).failed == 0


def test_flint_is_imported_only_on_first_use():
    import subprocess
    import sys

    code = ("import sys, athenakin as ak; a = 'flint' in sys.modules; "
            "f = ak.certified_forward_kinematics; b = 'flint' in sys.modules; "
            "ak.certified_forward_kinematics([-0.1, 0.1, 0.45], ak.default_rcm_frame()); "
            "print(a, b, 'flint' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "False False True"


# ------------------------------------------------------------------------------ CLI
def test_cli_fk_certify_table_and_json(capsys):
    import json

    from athenakin.cli import main

    assert main(["fk", "-0.10", "0.10", "0.45", "--certify"]) == 0
    out = capsys.readouterr().out
    assert "exactly 16 real solutions (proven)" in out and out.count("CERTIFIED") == 16
    assert main(["fk", "-0.10", "0.10", "0.45"]) == 0             # the angles in fk's range
    plain = capsys.readouterr().out.splitlines()[3:19]
    cert_rows = out.splitlines()[3:19]
    for row, crow in zip(plain, cert_rows, strict=True):
        u = [float(x) for x in row.split()[7:12]]
        mids = [float(part.split()[-1]) for part in crow.split("+-")[1:6]]
        assert all(-180 < m <= 180 for m in mids), crow
        np.testing.assert_allclose(mids, u, rtol=0, atol=1e-3)
    assert main(["fk", "-0.10", "0.10", "0.45", "--certify", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)["certificate"]
    assert data["complete"] and data["n_certified"] == 16
    cert = certified_forward_kinematics(Q_REF, T_REF, D)
    assert data["slots"][3]["p_m"] == [cert.p_lo[3], cert.p_hi[3]]
    assert np.array_equal(np.array(data["slots"][3]["u_rad"]),
                          np.stack([cert.u_lo[3], cert.u_hi[3]], axis=-1))


def test_cli_fk_certify_unreachable_and_missing_flint(capsys, monkeypatch):
    import builtins

    from athenakin.cli import main

    assert main(["fk", "-0.10", "0.10", "2.0", "--certify"]) == 0
    out = capsys.readouterr().out
    assert "exactly 0 real solutions (proven)" in out and "STROKE_LIMIT" in out
    real_import = builtins.__import__

    def no_flint(name, *args, **kwargs):
        if name == "flint":
            raise ImportError("No module named 'flint'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_flint)
    assert main(["fk", "-0.10", "0.10", "0.45", "--certify"]) != 0
    assert "pip install 'athenakin[certified]'" in capsys.readouterr().err


def test_input_tol_huge_int_named():
    """Audit of issue 13: input_tol = 10**400 was an OverflowError."""
    with pytest.raises(InvalidInputError, match="input_tol"):
        certified_forward_kinematics([-0.1, 0.1, 0.45], ak.default_rcm_frame(), input_tol=10**400)

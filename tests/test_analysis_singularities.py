"""Every singularity condition at exact singular configurations and at distances 1e-3..1e-12."""

import numpy as np
import pytest

import athenakin as ak
from athenakin.analysis import (
    CONDITIONS,
    DEFAULT_TOL,
    parallel_jacobian,
    passive_jacobian,
    singular_sets_within_strokes,
    singularities,
    singularity_loci,
)
from athenakin.chain import ups_transform
from athenakin.testing import random_configurations

SEED = 7
DESIGN = ak.Design.default()
DISTANCES = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]
#: relative accuracy of a closed-form value at distance delta: rounding of O(1) m inputs
#: (about 1e-16 m absolute) over delta, with a margin
def _rtol(delta):
    return 1e-12 + 2e-15 / delta


def _check_near_flags(name, build, delta, *, design=DESIGN, **kw):
    """near flips between tol = delta/10 and tol = 10 delta."""
    q, T = build(delta)
    assert singularities(q, T, design, tol={name: 10 * delta}, **kw).conditions[name].near
    assert not singularities(q, T, design, tol={name: delta / 10}, **kw).conditions[name].near


# --------------------------------------------------------------------------------------
# parallel module
# --------------------------------------------------------------------------------------
H = -0.24  # an h where both tangencies lie within the q3 strokes


def _tangency(h):
    r1 = np.sqrt(DESIGN.l1 ** 2 - h * h)
    d = np.hypot(np.sqrt(DESIGN.l3 ** 2 - h * h) + DESIGN.l2, DESIGN.l5)
    return d - r1, d + r1


def build_ab(delta):
    return np.array([-delta, delta, 0.45]), None


def build_external(delta):
    return np.array([H, -H, _tangency(H)[1] - delta]), None


def build_internal(delta):
    return np.array([H, -H, _tangency(H)[0] + delta]), None


def build_rail(delta):
    return np.array([-(DESIGN.l3 - delta), DESIGN.l3 - delta, 0.45]), None


PARALLEL_CASES = [
    # name, builder, measure that vanishes, exponent of its scaling with the distance
    ("ab_coincide", build_ab, "parallel_sigma_min", 1.0),
    ("circles_tangent", build_external, "parallel_inverse_sigma_min", 0.5),
    ("circles_tangent", build_internal, "parallel_inverse_sigma_min", 0.5),
    ("d_on_rail", build_rail, "parallel_inverse_sigma_min", 0.5),
    ("d_on_rail", build_rail, "parallel_sigma_min", 0.5),
]


@pytest.mark.parametrize("mode", [1, -1])
@pytest.mark.parametrize("name, build, measure, power", PARALLEL_CASES)
def test_parallel_condition_at_distances(name, build, measure, power, mode):
    values, meas = [], []
    for delta in DISTANCES:
        q, _ = build(delta)
        rep = singularities(q, design=DESIGN, mode=mode)
        assert bool(rep.assembled)
        v = float(rep.conditions[name].value)
        np.testing.assert_allclose(v, delta, rtol=_rtol(delta) * 10)
        assert bool(rep.conditions[name].near) == (v <= DEFAULT_TOL)
        values.append(v)
        meas.append(float(rep.measures[measure]))
    _assert_power_law(meas, power)


def _assert_power_law(meas, power):
    """The measure vanishes like distance**power (log-log slope over 1e-6 .. 1e-12)."""
    meas, dist = np.abs(np.array(meas)), np.array(DISTANCES)
    assert np.all(meas > 0)
    slope = np.diff(np.log(meas[3:])) / np.diff(np.log(dist[3:]))
    np.testing.assert_allclose(slope, power, atol=0.02)
    ratio = meas / dist ** power
    assert np.all((ratio > 0.5 * ratio[-1]) & (ratio < 2 * ratio[-1]))


def test_default_tolerance_value():
    assert DEFAULT_TOL == 1e-6
    assert singularities([-1e-6, 1e-6, 0.45]).conditions["ab_coincide"].near
    assert not singularities([-2e-6, 2e-6, 0.45]).conditions["ab_coincide"].near


@pytest.mark.parametrize("name, build", [("ab_coincide", build_ab),
                                         ("circles_tangent", build_external),
                                         ("circles_tangent", build_internal),
                                         ("d_on_rail", build_rail)])
@pytest.mark.parametrize("delta", DISTANCES)
def test_parallel_near_flags(name, build, delta):
    _check_near_flags(name, build, delta)


def test_ab_coincide_exact_refutes_no_inverse_singularity():
    """At h = 0 the rate (1, -1, 0) moves nothing: an inverse singularity inside the strokes."""
    q = np.array([0.02, 0.02, 0.45])
    J = parallel_jacobian(q, DESIGN)
    np.testing.assert_allclose(J @ np.array([1.0, -1.0, 0.0]), 0.0, atol=1e-15)
    assert np.linalg.matrix_rank(J, tol=1e-12) == 2
    rep = singularities(q, design=DESIGN, tol=0.0)
    assert rep.near_names() == ["ab_coincide"]
    assert float(rep.measures["parallel_sigma_min"]) == 0.0
    assert float(rep.measures["parallel_condition"]) == np.inf
    # within the stroke limits and accepted by the core's A/B check
    fk = ak.parallel.parallel_forward_kinematics(q, DESIGN)
    assert fk.valid[0] and fk.valid[1]
    # the IK of a point at the largest radius l1 + l4 lands on it; h = sqrt(l1^2 - r1^2)
    # turns the rounding of r1 (1e-17 m) into 1e-9 m: the amplification of an inverse
    # singularity
    ik = ak.parallel.parallel_ik_from_position([0.0, 0.0, DESIGN.l1 + DESIGN.l4], DESIGN)
    assert abs(ik.q[0] - ik.q[1]) < 1e-7


@pytest.mark.parametrize("build", [build_external, build_internal])
def test_tangency_exact(build):
    q, _ = build(0.0)
    for mode in (1, -1):
        rep = singularities(q, design=DESIGN, mode=mode, tol=1e-15)
        assert "circles_tangent" in rep.near_names()
        assert float(rep.measures["parallel_inverse_sigma_min"]) < 1e-7
        assert float(rep.measures["half_chord"]) < 1e-7
    # the core reports the two modes merged
    fk = ak.parallel.parallel_forward_kinematics(q, DESIGN)
    assert fk.valid[0] and fk.reason[1] == ak.Reason.CIRCLES_TANGENT


def test_d_on_rail_exact():
    q, _ = build_rail(0.0)
    rep = singularities(q, design=DESIGN, tol=0.0)
    assert rep.near_names() == ["d_on_rail"]
    assert float(rep.measures["parallel_sigma_min"]) == 0.0
    assert float(rep.measures["parallel_inverse_sigma_min"]) == 0.0
    # beyond: not assembled, the core says the links are too short
    q2 = np.array([-0.26, 0.26, 0.45])
    assert not bool(singularities(q2, design=DESIGN).assembled)
    assert float(singularities(q2, design=DESIGN).conditions["d_on_rail"].value) < 0
    assert ak.parallel.parallel_forward_kinematics(q2, DESIGN).reason[0] == \
        ak.Reason.LINK_TOO_SHORT


# k1 degenerates (r1 -> 0) only if l1 <= l3: a design built for it
K1_DESIGN = ak.Design(l1=0.2, l2=0.1, l3=0.25, l4=0.15, l5=0.1)


def build_k1(delta):
    h = K1_DESIGN.l1 - delta
    d = np.hypot(np.sqrt(K1_DESIGN.l3 ** 2 - h * h) + K1_DESIGN.l2, K1_DESIGN.l5)
    return np.array([-h, h, d]), None


def test_k1_degenerate_at_distances():
    meas = []
    for delta in DISTANCES:
        q, _ = build_k1(delta)
        rep = singularities(q, design=K1_DESIGN)
        assert bool(rep.assembled)
        np.testing.assert_allclose(float(rep.conditions["k1_degenerate"].value), delta,
                                   rtol=_rtol(delta) * 10)
        meas.append(float(rep.measures["parallel_inverse_sigma_min"]))
        _check_near_flags("k1_degenerate", build_k1, delta, design=K1_DESIGN)
    _assert_power_law(meas, 0.5)
    q, _ = build_k1(0.0)
    rep = singularities(q, design=K1_DESIGN, tol=0.0)
    assert "k1_degenerate" in rep.near_names() and not bool(rep.assembled)


def test_k2_degenerate_and_stroke_limit_values():
    for delta in DISTANCES:
        rep = singularities([-0.1, 0.1, delta], design=DESIGN)
        np.testing.assert_allclose(float(rep.conditions["k2_degenerate"].value), delta, rtol=1e-15)
        # for the default design k2 cannot shrink onto k1 (d >= l5 > l1 >= r1)
        assert not bool(rep.assembled)
        q = np.array([DESIGN.q_max[0] - delta, 0.2, 0.45])
        v = float(singularities(q, design=DESIGN).conditions["stroke_limit"].value)
        np.testing.assert_allclose(v, delta, rtol=_rtol(delta) * 10)
    assert float(singularities([0.2, 0.25, 0.45]).conditions["stroke_limit"].value) < 0


def test_default_design_never_assembles_small_q3():
    q3 = np.linspace(1e-6, 0.1, 50)
    q = np.stack([np.full(50, -0.1), np.full(50, 0.1), q3], axis=-1)
    assert not np.any(singularities(q, design=DESIGN).assembled)


# --------------------------------------------------------------------------------------
# serial chain, paper-form IK, tool tip: configurations built through the closure
# --------------------------------------------------------------------------------------
Q_REF = ak.robot.REFERENCE_Q
T_B_S = ak.parallel.parallel_forward_kinematics(Q_REF, DESIGN).T_b_s[0]
U0 = np.array([0.5, 0.7, 0.3, 1.0, 0.4])
P0 = 0.2


def _setup(p, u):
    return Q_REF, T_B_S @ ups_transform(p, np.asarray(u, float))


SERIAL_CASES = {
    # name: (builder (p, u) at distance delta, closed form value at delta, measure, power)
    "ujoint": (lambda e: (P0, U0 + [0, e - U0[1], 0, 0, 0]), np.sin, "serial_sigma_min", 1),
    "wrist": (lambda e: (P0, U0 + [0, 0, 0, e - U0[3], 0]), np.sin, "serial_sigma_min", 1),
    "p_zero": (lambda e: (e, U0), lambda e: e, "serial_det", 2),
    "ik_cos_u1": (lambda e: (P0, U0 + [np.pi / 2 + e - U0[0], 0, 0, 0, 0]), np.sin,
                  "ik_sigma_min", 1),
    "ik_sin_u1_sin_u2": (lambda e: (P0, U0 + [e - U0[0], np.pi / 2 - U0[1], 0, 0, 0]), np.sin,
                         "ik_sigma_min", 1),
    "tip_at_rcm": (lambda e: (DESIGN.tool_length + e, U0), lambda e: e, "tool_tip_sigma_min", 1),
}


@pytest.mark.parametrize("name", list(SERIAL_CASES))
def test_serial_ik_instrument_conditions_at_distances(name):
    build, exact, measure, power = SERIAL_CASES[name]
    meas = []
    for delta in DISTANCES:
        q, T = _setup(*build(delta))
        rep = singularities(q, T, DESIGN)
        np.testing.assert_allclose(float(rep.conditions[name].value), exact(delta),
                                   rtol=2e-3 if delta < 1e-9 else 1e-5)
        meas.append(abs(float(rep.measures[measure])))
        _check_near_flags(name, lambda e, b=build: _setup(*b(e)), delta)
    _assert_power_law(meas, power)


@pytest.mark.parametrize("name", list(SERIAL_CASES))
def test_serial_ik_instrument_conditions_exact(name):
    q, T = _setup(*SERIAL_CASES[name][0](0.0))
    rep = singularities(q, T, DESIGN, tol=1e-14)
    assert name in rep.near_names()
    assert float(rep.conditions[name].value) <= 1e-15


def test_exact_serial_singularities_are_those_the_core_reports():
    sol = ak.forward_kinematics(*_setup(*SERIAL_CASES["ujoint"][0](0.0)), DESIGN, errors="flag")
    assert np.any(sol.reason[:8] == ak.Reason.UJOINT_SINGULAR)
    sol = ak.forward_kinematics(*_setup(*SERIAL_CASES["wrist"][0](0.0)), DESIGN, errors="flag")
    assert np.any(sol.reason[:8] == ak.Reason.WRIST_SINGULAR)
    for name in ("ik_cos_u1", "ik_sin_u1_sin_u2"):
        p, u = SERIAL_CASES[name][0](0.0)
        _, T = _setup(p, u)
        _, passive = ak.inverse_kinematics(T, u[2:], DESIGN, errors="flag")
        assert passive.reason == ak.Reason.IK_SINGULAR
        # ... and the map q -> (u3, u4, u5) loses rank there
        Jp = passive_jacobian(Q_REF, p, u, DESIGN)
        assert np.linalg.svd(Jp[3:], compute_uv=False)[-1] < 1e-12


def test_conditions_match_the_fk_angles_of_all_slots():
    rc = random_configurations(1000, DESIGN, rng=SEED)
    rep = singularities(rc.q, rc.T_b_e, DESIGN, mode=rc.mode, jacobians=False)
    sol = ak.forward_kinematics(rc.q, rc.T_b_e, DESIGN, errors="flag")
    same = sol.mode == rc.mode[:, None]
    u, p = sol.u, sol.p
    expect = {"ujoint": np.abs(np.sin(u[..., 1])), "wrist": np.abs(np.sin(u[..., 3])),
              "ik_cos_u1": np.abs(np.cos(u[..., 0])),
              "ik_sin_u1_sin_u2": np.abs(np.sin(u[..., 0]) * np.sin(u[..., 1])),
              "p_zero": np.abs(p), "tip_at_rcm": np.abs(np.abs(p) - DESIGN.tool_length)}
    for name, e in expect.items():
        v = np.broadcast_to(rep.conditions[name].value[:, None], e.shape)
        ok = same & sol.valid
        assert ok.sum() >= 8 * 1000 - 10
        np.testing.assert_allclose(v[ok], e[ok], rtol=0, atol=1e-9, err_msg=name)


# --------------------------------------------------------------------------------------
# report structure, loci, design findings
# --------------------------------------------------------------------------------------
def test_report_structure_and_batch():
    rc = random_configurations(50, DESIGN, rng=SEED + 1)
    rep = singularities(rc.q.reshape(5, 10, 3), rc.T_b_e.reshape(5, 10, 4, 4), DESIGN,
                        mode=rc.mode.reshape(5, 10))
    assert list(rep.conditions) == list(CONDITIONS)
    for c in rep.conditions.values():
        assert c.value.shape == (5, 10) and c.near.shape == (5, 10)
        assert c.kind and c.meaning and c.test and c.unit in ("m", "1")
    assert rep.near_any.shape == (5, 10) and not rep.near_any.any()
    one = singularities(rc.q[13], rc.T_b_e[13], DESIGN, mode=rc.mode[13])
    for k, c in one.conditions.items():
        assert float(c.value) == pytest.approx(float(rep.conditions[k].value[1, 3]), abs=1e-15)
    assert set(rep.values((1, 3))) == set(CONDITIONS)
    only_parallel = singularities(rc.q, design=DESIGN, mode=rc.mode)
    assert set(only_parallel.conditions) == {"circles_tangent", "d_on_rail", "k1_degenerate",
                                             "ab_coincide", "k2_degenerate", "stroke_limit"}


def test_tolerance_arguments():
    with pytest.raises(ak.InvalidInputError, match="unknown condition"):
        singularities([-0.1, 0.1, 0.45], tol={"no_such": 1.0})
    with pytest.raises(ak.InvalidInputError, match="non-negative"):
        singularities([-0.1, 0.1, 0.45], tol=-1.0)
    with pytest.raises(TypeError, match="tol: expected"):
        singularities([-0.1, 0.1, 0.45], tol="big")
    rep = singularities([-0.1, 0.1, 0.45], tol=0.5)
    assert set(rep.near_names()) == set(rep.conditions)


def test_loci_are_the_zero_sets():
    loci = singularity_loci(DESIGN, n=101)
    h = loci["h"][(loci["h"] < -1e-3)]
    for key in ("q3_external", "q3_internal"):
        q3 = loci[key][(loci["h"] < -1e-3)]
        q = np.stack([h, -h, q3], axis=-1)
        v = singularities(q, design=DESIGN).conditions["circles_tangent"].value
        assert np.max(v) < 1e-15
        assert np.max(singularities(q, design=DESIGN).measures["half_chord"]) < 1e-7


def test_default_design_findings():
    f = singular_sets_within_strokes(DESIGN)
    assert f["ab_coincide"]["reachable"]          # q1 = q2 allowed by the strokes
    assert f["d_on_rail"]["reachable"]            # |q1 - q2| up to 0.6 m > 2 l3
    assert not f["k1_degenerate"]["reachable"]
    assert not f["k2_degenerate"]["reachable"]
    assert f["circles_tangent"]["reachable"]      # the modes can meet within the strokes
    lo, hi = f["mode_safe_q3"]["value"]
    assert DESIGN.q_min[2] < lo < hi < DESIGN.q_max[2]
    assert (round(lo, 4), round(hi, 4)) == (0.2546, 0.5781)     # quoted in README, docs
    # check the safe interval: on a grid of allowed h the circles intersect with margin
    h = np.linspace(-DESIGN.l3 + 1e-9, 0.0, 2001)
    for q3 in (lo + 1e-6, hi - 1e-6):
        q = np.stack([h, -h, np.full_like(h, q3)], axis=-1)
        rep = singularities(q, design=DESIGN)
        assert np.all(rep.assembled) and np.all(rep.measures["half_chord"] > 0)
    # just outside it some h is tangent or apart
    for q3 in (lo - 1e-4, hi + 1e-4):
        q = np.stack([h, -h, np.full_like(h, q3)], axis=-1)
        assert not np.all(singularities(q, design=DESIGN).assembled)


@pytest.mark.parametrize("name", ["ab_coincide", "circles_tangent", "d_on_rail", "ujoint",
                                  "wrist", "p_zero", "ik_cos_u1", "ik_sin_u1_sin_u2",
                                  "tip_at_rcm"])
def test_near_singular_configurations(name):
    from athenakin.analysis import MEASURE_OF, near_singular_configurations

    dist = np.array(DISTANCES)
    q, T = near_singular_configurations(name, dist, DESIGN)
    assert q.shape == (dist.size, 3) and T.shape == (dist.size, 4, 4)
    rep = singularities(q, T, DESIGN)
    np.testing.assert_allclose(rep.conditions[name].value, dist, rtol=2e-3)
    measure, power = MEASURE_OF[name]
    _assert_power_law(list(rep.measures[measure]), power)


def test_near_singular_configurations_rejects_unknown_names():
    from athenakin.analysis import near_singular_configurations

    with pytest.raises(ak.InvalidInputError, match="name: expected one of"):
        near_singular_configurations("stroke_limit", [1e-3])


def test_audit_arguments_named():
    """Audit of issue 13: counts, tolerances and matrices are checked by name."""
    with pytest.raises(ak.InvalidInputError, match="n"):
        ak.analysis.singularity_loci(n=float("inf"))
    with pytest.raises(ak.InvalidInputError, match="n"):
        ak.analysis.singular_sets_within_strokes(n=10**400)
    assert len(ak.analysis.singularity_loci(n=11.0)["h"]) == 11      # an integral float
    with pytest.raises(ak.InvalidInputError, match="tol"):
        ak.analysis.singularities([-0.1, 0.1, 0.45], tol=10**400)
    with pytest.raises((TypeError, ValueError), match="distances"):
        ak.analysis.near_singular_configurations("ab_coincide", 10**400)
    for bad in (None, "J", np.zeros(3), np.zeros((0, 3))):
        with pytest.raises((TypeError, ValueError), match="J"):
            ak.analysis.sigma_min(bad)
    np.testing.assert_allclose(ak.analysis.condition_number(np.eye(3)), 1.0)

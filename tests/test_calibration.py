"""athenakin.calibration: measurement model, identifiability, solver, bad input."""

import dataclasses
import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin import calibration as cal
from athenakin.calibration._model import parameter_vector, predict
from athenakin.errors import InvalidInputError, KinematicsError

D = ak.Design.default()
T = ak.default_rcm_frame(D)
TRUTH_KEYS = ("l1", "l2", "l3", "l4", "l5", "tool_length", "q1_offset", "q2_offset",
              "q3_offset", "rcm_x", "rcm_y", "rcm_z")


def truth(data, names):
    return np.array([data.true_parameters[n] for n in names])


def rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


# --------------------------------------------------------------------------------------
# measurement model
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize("mode", [1, -1])
def test_model_tip_matches_forward_kinematics(mode):
    """The tip of the model is O_s + L z_3 of the FK slot (mode, p > 0), z_3 from the U-joint."""
    q = cal.random_poses(15, T, D, mode=mode, rng=10)   # mode -1 is rare within the strokes
    sol = ak.forward_kinematics(q, T, D)
    k = ak.robot.slot_index(mode, 1, 1, 1)
    assert np.all(sol.valid[:, k])
    u1, u2 = sol.u[:, k, 0], sol.u[:, k, 1]
    R = np.array([sol.T_b_s[i, k, :3, :3] @ rot_z(u1[i]) @ rot_x(np.pi / 2) @ rot_z(u2[i])
                  @ rot_x(np.pi / 2) for i in range(len(q))])
    tip_fk = sol.T_b_s[:, k, :3, 3] + D.tool_length * R[:, :, 2]
    pr = predict(parameter_vector(D, T[:3, 3]), q, np.full(len(q), float(mode)))
    assert_allclose(pr.tip_base, tip_fk, rtol=0, atol=1e-12)
    assert_allclose(pr.rho, sol.p[:, k], rtol=0, atol=1e-12)


def test_model_tip_round_trip_through_tool_tip_ik():
    q = cal.random_poses(50, T, D, rng=11)
    pr = predict(parameter_vector(D, T[:3, 3]), q, np.ones(len(q)))
    tip_e = (pr.tip_base - T[:3, 3]) @ T[:3, :3]
    q_back, res = ak.q_from_tool_tip(T, tip_e, D)
    assert np.all(res.valid)
    assert_allclose(q_back, q, rtol=0, atol=1e-11)


@pytest.mark.parametrize("frame", ["base", "tracker"])
def test_model_jacobian_matches_central_differences(frame):
    q = cal.random_poses(25, T, D, rng=12)
    theta = parameter_vector(D, T[:3, 3], q_offset=np.array([1e-4, -2e-4, 3e-4]),
                             registration=np.array([0.3, -0.2, 0.1, 0.5, -0.4, 0.9]))
    R0 = rot_z(0.7) @ rot_x(-0.3) if frame == "tracker" else None
    m = np.ones(len(q))
    pr = predict(theta, q, m, R0=R0, jacobian=True)
    eps = 1e-6
    for i in range(theta.size):
        e = np.zeros(theta.size)
        e[i] = eps
        a, b = predict(theta + e, q, m, R0=R0), predict(theta - e, q, m, R0=R0)
        assert_allclose(pr.J_tip[:, :, i], (a.tip - b.tip) / (2 * eps), rtol=0, atol=2e-7)
        assert_allclose(pr.J_axis[:, :, i], (a.axis - b.axis) / (2 * eps), rtol=0, atol=2e-7)
    for i in range(3):   # readings: the same as the offsets
        e = np.zeros(3)
        e[i] = eps
        a, b = predict(theta, q + e, m, R0=R0), predict(theta, q - e, m, R0=R0)
        assert_allclose(pr.J_q[:, :, i], (a.tip - b.tip) / (2 * eps), rtol=0, atol=2e-7)


def test_model_reading_jacobian_is_the_package_tool_tip_jacobian():
    q = cal.random_poses(30, T, D, rng=14)
    pr = predict(parameter_vector(D, T[:3, 3]), q, np.ones(len(q)), jacobian=True)
    J = ak.analysis.tool_tip_jacobian(q, T, D)
    assert_allclose(pr.J_q, J, rtol=1e-9, atol=1e-12)


# --------------------------------------------------------------------------------------
# noise-free recovery
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize("params, frame, kw", [
    (None, "base", {}),
    (["default", "offsets"], "base", {"offset_std": 3e-4}),
    (["default", "offsets", "rcm"], "base", {"offset_std": 3e-4, "rcm_std": 1e-3}),
    (["default", "q3_offset"], "tracker",
     {"offset_std": 3e-4, "true": {"q1_offset": 0.0, "q2_offset": 0.0}}),
    (["default", "offsets"], "base", {"offset_std": 3e-4, "axes": True}),
])
def test_noise_free_data_recover_parameters_to_1e_9(params, frame, kw):
    axes = kw.pop("axes", False)
    data = cal.synthetic_measurements(T, D, n=40, frame=frame, axes=axes, rng=20,
                                      options=cal.SyntheticOptions(noise=0.0, axis_noise=0.0,
                                                                   **kw))
    res = cal.calibrate(data.q, data.tips, T, D, params=params, frame=frame, axes=data.axes)
    robot = [n for n in res.names if n in TRUTH_KEYS]
    est = np.array([res.parameters[n] for n in robot])
    assert_allclose(est, truth(data, robot), rtol=0, atol=1e-9)
    assert res.rms_after < 1e-11 and not np.any(res.outliers)
    if frame == "tracker":
        assert_allclose(res.T_t_b, data.T_t_b, rtol=0, atol=1e-9)
    assert res.design.l3 == res.parameters["l3"]
    assert res.design.q_min == D.q_min and res.design.ab_order == D.ab_order


def test_interface_of_the_checks_default_parameters_and_design():
    data = cal.synthetic_measurements(T, D, n=30, rng=21, options=cal.SyntheticOptions(noise=0.0))
    res = cal.calibrate(data.q, data.tips, T, D)
    assert res.names == cal.DEFAULT_PARAMETERS
    assert isinstance(res.design, ak.Design)
    for n in cal.DEFAULT_PARAMETERS:
        assert abs(getattr(res.design, n) - getattr(data.true_design, n)) < 1e-9
    assert res.covariance.shape == (6, 6) and res.std.shape == (6,)
    assert res.residuals_before.shape == (30, 3) and res.rms_before > 1e-4
    lazy = ak.calibration.calibrate(data.q, data.tips, T, D)   # the lazy attribute works
    assert lazy.design == res.design
    # a name of its own, derived from the reference's (issue 30: it kept the reference's)
    assert res.design.name == f"{D.name}, calibrated" != D.name
    unnamed = cal.calibrate(data.q, data.tips, T, dataclasses.replace(D, name=""))
    assert unnamed.design.name == "calibrated design"


def test_mode_auto_picks_each_rows_assembly_mode():
    exact = cal.SyntheticOptions(noise=0.0, perturbation=0.0, true={"l1": 0.3003, "l4": 0.1498})
    a = cal.synthetic_measurements(T, D, n=10, mode=-1, rng=23, options=exact)
    q = np.concatenate([a.q, cal.random_poses(20, T, D, rng=24)])
    b = cal.synthetic_measurements(T, D, q=q[10:], rng=23, options=exact)
    tips = np.concatenate([a.tips, b.tips])
    res = cal.calibrate(q, tips, T, D, mode="auto")
    assert res.mode.tolist() == [-1] * 10 + [1] * 20
    assert_allclose([res.design.l1, res.design.l4], [0.3003, 0.1498], rtol=0, atol=1e-9)
    with pytest.raises(InvalidInputError, match="frame='base'"):
        cal.calibrate(q, tips, T, D, mode="auto", frame="tracker")


def test_mode_minus_one_is_followed():
    data = cal.synthetic_measurements(T, D, n=12, mode=-1, rng=22,
                                      options=cal.SyntheticOptions(noise=0.0))
    res = cal.calibrate(data.q, data.tips, T, D, mode=-1)
    assert_allclose(res.estimates, truth(data, res.names), rtol=0, atol=1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cal.CalibrationWarning)
        try:
            wrong = cal.calibrate(data.q, data.tips, T, D, mode=1,
                                  options=cal.CalibrationOptions(max_bad_fraction=1.0))
        except cal.CalibrationError as exc:
            assert "assembly mode" in str(exc)
        else:   # the other assembly mode does not explain the data
            assert wrong.rms_after > 1e-4


# --------------------------------------------------------------------------------------
# identifiability
# --------------------------------------------------------------------------------------
def test_tracker_frame_names_the_rail_shift_combination():
    q = cal.random_poses(30, T, D, rng=30)
    with pytest.raises(cal.NotIdentifiableError, match="q1_offset.*q2_offset") as ei:
        data = cal.synthetic_measurements(T, D, q=q, frame="tracker", rng=30,
                                          options=cal.SyntheticOptions(noise=0.0))
        cal.calibrate(data.q, data.tips, T, D, params=["default", "offsets", "rcm"],
                      frame="tracker")
    (combo,) = ei.value.combinations
    assert combo.startswith("+1 q1_offset +1 q2_offset +1 rcm_x")
    assert "shift of the base along x" in combo
    rep = cal.identifiability(q, T, D, params=["default", "offsets", "rcm"], frame="tracker")
    assert not rep.identifiable and rep.null_vectors.shape == (1, 18)
    assert cal.identifiability(q, T, D, params=["default", "offsets"],
                               frame="tracker").identifiable


@pytest.mark.parametrize("params", [None, ["default", "offsets"], ["default", "rcm"],
                                    ["default", "offsets", "rcm"], ["lengths"]])
def test_base_frame_parameter_sets_are_identifiable(params):
    rep = cal.identifiability(cal.random_poses(30, T, D, rng=31), T, D, params=params)
    assert rep.identifiable and not rep.weak and rep.combinations == ()
    assert np.all(np.diff(rep.singular_values) <= 0)


def test_too_few_poses_is_a_named_error_with_combinations():
    q = cal.random_poses(2, T, D, rng=32)
    rep = cal.identifiability(q, T, D, params=["default", "offsets"])
    assert not rep.identifiable and len(rep.combinations) == 3   # 9 parameters, 6 rows
    data = cal.synthetic_measurements(T, D, q=q, rng=32, options=cal.SyntheticOptions(noise=0.0))
    with pytest.raises(cal.NotIdentifiableError, match="too few poses"):
        cal.calibrate(data.q, data.tips, T, D, params=["default", "offsets"])


def test_poses_that_cannot_separate_are_refused_or_warned():
    """Poses with q1 - q2 fixed: r1 and m_y are constant, so l1 and l4 (or l2, l3) mix."""
    rng = np.random.default_rng(33)
    base = cal.random_poses(1, T, D, rng=33)[0]
    s = rng.uniform(-0.02, 0.02, 25)
    q = np.stack([base[0] + s, base[1] + s, base[2] + rng.uniform(-0.03, 0.03, 25)], axis=1)
    data = cal.synthetic_measurements(T, D, q=q, rng=33, options=cal.SyntheticOptions(noise=0.0))
    with pytest.raises(cal.NotIdentifiableError, match="inseparable") as ei:
        cal.calibrate(data.q, data.tips, T, D)
    assert any("l2" in c and "l3" in c for c in ei.value.combinations)
    assert isinstance(ei.value, KinematicsError)
    with pytest.warns(cal.CalibrationWarning, match="not identifiable"):
        cal.calibrate(data.q, data.tips, T, D,
                      options=cal.CalibrationOptions(on_unidentifiable="warn"))


def test_parameter_without_effect_is_named():
    """A parameter whose Jacobian column is zero is named as having no effect."""
    J = np.array([[1.0, 0.0], [0.0, 0.0], [2.0, 0.0]])
    rep = cal.analyse_jacobian(J, ("l1", "q3_offset"))
    assert not rep.identifiable
    assert rep.combinations == ("+1 q3_offset: q3_offset has no effect on these measurements",)


# --------------------------------------------------------------------------------------
# experiment design
# --------------------------------------------------------------------------------------
def test_d_optimal_plan_beats_random_poses():
    params = ["default", "offsets"]
    plan = cal.plan_poses(20, T, D, params=params, n_candidates=600, rng=40)
    assert plan.q.shape == (20, 3) and len(np.unique(plan.q, axis=0)) == 20
    assert np.all(cal.check_measurements(plan.q, T, D).usable)
    def logdet(q):
        rep = cal.identifiability(q, T, D, params=params)
        Jn = rep.singular_values
        return 2 * np.sum(np.log(Jn)) + 2 * np.sum(np.log(rep.column_norms))
    rnd = [logdet(cal.random_poses(20, T, D, rng=41 + k)) for k in range(5)]
    assert logdet(plan.q) > max(rnd)
    assert plan.identifiability.identifiable


def test_plan_rejects_too_few_poses():
    with pytest.raises(InvalidInputError, match="3 n > 9"):
        cal.plan_poses(3, T, D, params=["default", "offsets"])


# --------------------------------------------------------------------------------------
# bad input
# --------------------------------------------------------------------------------------
def test_mismatched_lengths_and_shapes():
    data = cal.synthetic_measurements(T, D, n=20, rng=50)
    with pytest.raises(InvalidInputError, match="mismatched lengths"):
        cal.calibrate(data.q, data.tips[:-1], T, D)
    with pytest.raises(InvalidInputError, match=r"expected shape \(N, 3\)"):
        cal.calibrate(data.q[0], data.tips[0], T, D)
    with pytest.raises(InvalidInputError, match="expected shape"):
        cal.calibrate(data.q[:, :2], data.tips, T, D)
    with pytest.raises(ValueError, match="unknown parameter 'l7'"):
        cal.calibrate(data.q, data.tips, T, D, params=["l7"])
    with pytest.raises(ValueError, match="frame='tracker'"):
        cal.calibrate(data.q, data.tips, T, D, params=["reg_tx"])
    with pytest.raises(InvalidInputError, match="sigma: expected a positive number"):
        cal.calibrate(data.q, data.tips, T, D, options=cal.CalibrationOptions(sigma=-1.0))
    with pytest.raises(ValueError, match="loss"):
        cal.calibrate(data.q, data.tips, T, D, options=cal.CalibrationOptions(loss="l2"))
    with pytest.raises(TypeError, match="expected athenakin.Design"):
        cal.calibrate(data.q, data.tips, T, "design")


def test_a_few_bad_rows_are_flagged_and_excluded():
    data = cal.synthetic_measurements(T, D, n=40, rng=51, options=cal.SyntheticOptions(noise=0.0))
    q, tips = data.q.copy(), data.tips.copy()
    tips[3, 1] = np.nan
    q[7, 0] = np.inf
    q[9] = [0.09, 0.299, 0.2]   # outside the nominal workspace (links cannot span A-B)
    with pytest.warns(cal.CalibrationWarning, match="3 of 40 rows excluded"):
        res = cal.calibrate(q, tips, T, D)
    assert np.flatnonzero(res.excluded).tolist() == [3, 7, 9]
    assert res.check.reason[3] == ak.Reason.NONFINITE_INPUT
    assert res.check.reason[9] != 0
    assert np.all(np.isnan(res.residuals_after[[3, 7, 9]]))
    assert_allclose(res.estimates, truth(data, res.names), rtol=0, atol=1e-9)
    with pytest.raises(InvalidInputError, match="3 of 40 rows cannot be used"):
        cal.calibrate(q, tips, T, D, options=cal.CalibrationOptions(bad_rows="raise"))


def test_many_bad_rows_are_refused():
    data = cal.synthetic_measurements(T, D, n=20, rng=52)
    tips = data.tips.copy()
    tips[:5] = np.nan
    with pytest.raises(InvalidInputError, match="more than 10%"):
        cal.calibrate(data.q, tips, T, D)


def test_robust_loss_flags_the_outliers_and_matches_the_clean_fit():
    data = cal.synthetic_measurements(T, D, n=80, rng=53, options=cal.SyntheticOptions(
        noise=20e-6, outlier_fraction=0.05))
    with pytest.warns(cal.CalibrationWarning, match="outliers"):
        res = cal.calibrate(data.q, data.tips, T, D,
                            options=cal.CalibrationOptions(loss="soft_l1"))
    assert np.array_equal(res.outliers, data.outliers)
    clean = cal.calibrate(data.q[~data.outliers], data.tips[~data.outliers], T, D)
    assert_allclose(res.estimates, clean.estimates, rtol=0, atol=1e-12)
    assert_allclose(res.std, clean.std, rtol=1e-9)
    with pytest.warns(cal.CalibrationWarning, match="outliers"):
        lin = cal.calibrate(data.q, data.tips, T, D)   # flagged only
    assert np.all(lin.outliers[data.outliers])


def test_audit_options_named():
    """Audit of issue 13: options of the calibration reached numpy or float() unchecked
    (frame arrays, axis_weight=None, sigma=1e308 squared to inf, tol=None, mode=10**400)."""
    data = cal.synthetic_measurements(T, D, n=12, rng=3)
    bad = [({"frame": np.array(["base", "base"])}, "frame"), ({"axis_weight": None}, "axis_weight"),
           ({"sigma": 1e308}, "sigma"), ({"outlier_threshold": None}, "outlier_threshold"),
           ({"identifiability_tol": 10**400}, "tol"), ({"tol": "x"}, "tol"),
           ({"max_nfev": float("nan")}, "max_nfev")]
    for kw, match in bad:
        with pytest.raises((TypeError, ValueError), match=match):
            if "frame" in kw:
                cal.calibrate(data.q, data.tips, T, D, **kw)
            else:
                cal.calibrate(data.q, data.tips, T, D, options=cal.CalibrationOptions(**kw))
    with pytest.raises(InvalidInputError, match="mode"):
        cal.random_poses(3, T, D, mode=10**400)
    with pytest.raises(TypeError, match="margin"):
        cal.random_poses(3, T, D, margin="x")
    with pytest.raises(TypeError, match="rng"):
        cal.random_poses(3, T, D, rng="seed")
    for kw, match in (({"noise": 10**400}, "noise"), ({"true": 1.0}, "true"),
                      ({"outlier_fraction": float("inf")}, "outlier_fraction")):
        with pytest.raises((TypeError, ValueError), match=match):
            cal.synthetic_measurements(T, D, n=4, rng=1, options=cal.SyntheticOptions(**kw))
    with pytest.raises((TypeError, ValueError), match="J"):
        cal.analyse_jacobian(None, ("a",))


def test_audit_writers_and_plots_named(tmp_path):
    """Audit of issue 13: a result that is not a CalibrationResult, q=None, a non-str
    comment reached AttributeError / numpy tracebacks in the writers and plots."""
    for fn in (cal.calibration_toml, cal.plot_residuals, cal.plot_parameter_confidence,
               cal.tip_error_map):
        with pytest.raises(TypeError, match="result"):
            fn(None)
    with pytest.raises(TypeError, match="result"):
        cal.write_report(None, tmp_path / "r")
    with pytest.raises(TypeError, match="m"):
        cal.plot_tip_error_map(None)
    q = np.array([[-0.1, 0.1, 0.45]])
    with pytest.raises(TypeError, match="q"):
        cal.measurements_csv_text(None, q)
    with pytest.raises(ValueError, match="tips"):
        cal.measurements_csv_text(q, np.zeros((2, 3)))
    with pytest.raises(TypeError, match="comment"):
        cal.plan_csv_text(q, comment=1)
    assert cal.plan_csv_text(q).count("\n") == 3


def test_audit_identifiability_arguments_named():
    """Audit of issue 13: unknown parameter names (KeyError), frame arrays and a 400-digit
    depth reached the internals unchecked."""
    with pytest.raises(ValueError, match="names"):
        cal.analyse_jacobian(np.zeros((3, 3)), ("a", "b", "c"))
    data = cal.synthetic_measurements(T, D, n=12, rng=3)
    with pytest.raises(ValueError, match="frame"):
        cal.identifiability(data.q, T, D, frame=np.array(["base", "base"]))
    res = cal.calibrate(data.q, data.tips, T, D)
    for kw, match in (({"depth": 10**400}, "depth"), ({"resolution": (3, 10**9)}, "resolution")):
        with pytest.raises(ValueError, match=match):
            cal.tip_error_map(res, **kw)

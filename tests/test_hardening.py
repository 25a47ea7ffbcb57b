"""Regression tests of issue 23: the reproducers of the hostile-user campaign, one row each.

Every row is a call that once raised a raw exception, allocated without bound, returned
NaN without an error or a wrong result flagged valid. Each now raises a named error
whose message names the argument (``match``), or returns a correct value (the
``value`` tests). No row may allocate more than a few MB before it fails.
"""

from __future__ import annotations

import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import athenakin as ak
from athenakin import InvalidInputError, NotOnStudyQuadricError

D = ak.Design.default()
T = ak.default_rcm_frame(D)
REPO = Path(__file__).resolve().parents[1]


def _task():
    from athenakin.synthesis import Task

    return Task(rcm=T[:3, 3], axis=T[:3, 0], half_angle=0.3, depth=(0.05, 0.1))


def _bad_frame():
    TT = T.copy()
    TT[0, 3] = np.nan
    return TT


# (id, call, exception class, regex the message must match: it names the argument)
RAISES = [
    # --- wrong results returned as valid -----------------------------------------------
    ("tangent_tol_huge", lambda: ak.parallel.parallel_forward_kinematics(
        [-0.1, 0.1, 0.2], D, tangent_tol=0.5), InvalidInputError, r"^tangent_tol: .*\[0, 0\.001\]"),
    ("tangent_tol_inf_fk", lambda: ak.forward_kinematics(
        [-0.1, 0.1, 0.45], T, D, tangent_tol=np.inf), InvalidInputError, r"^tangent_tol"),
    ("closure_tol_huge", lambda: ak.forward_kinematics(
        [-0.1, 0.1, 0.45], T, D, closure_tol=1.0), InvalidInputError, r"^closure_tol"),
    ("mjcf_nul_name", lambda: ak.sim.mjcf_from_design(T, D, model_name="\x00"),
     InvalidInputError, r"^model_name: .*U\+0000"),
    ("urdf_nul_name", lambda: ak.sim.urdf_from_design(T, D, robot_name="a\x1bb"),
     InvalidInputError, r"^robot_name: .*U\+001B at position 1"),
    # --- NaN returned without an error -------------------------------------------------
    ("rcm_axis_zero", lambda: ak.synthesis.rcm_frame_from_axis([0, 0, 0], [0, 0, 0]),
     InvalidInputError, r"^axis: "),
    ("quaternion_zero", lambda: ak.study.rotation_from_quaternion([0, 0, 0, 0]),
     InvalidInputError, r"^x: .*non-zero"),
    ("study_1e160_off_quadric", lambda: ak.study.transform_from_study(np.full(8, 1e160)),
     NotOnStudyQuadricError, r"^X: "),
    ("paper_1e300_off_quadric", lambda: ak.study.paper_matrix_from_study(np.full(8, 1e300)),
     NotOnStudyQuadricError, r"^X: "),
    # --- sizes never bounded -----------------------------------------------------------
    ("circle_points_n", lambda: ak.plot.circle_points([0, 0, 0], 0.1, n=10**9),
     InvalidInputError, r"^n: .*<= 100,000"),
    ("arc_points_n", lambda: ak.plot.arc_points([0, 0, 0], [1, 0, 0], [0, 1, 0], 0.1, n=10**9),
     InvalidInputError, r"^n: "),
    ("cone_path_n", lambda: ak.plot.instrument_cone_path(10**9, T),
     InvalidInputError, r"^n: "),
    ("inverse_step_n", lambda: ak.app.inverse_step(ak.app.app_setup(T, D, backend="numpy"),
                                                   [0.1, 0, 0], [0.1, 0, 0],
                                                   ak.robot.REFERENCE_Q, n=10**9),
     InvalidInputError, r"^n: "),
    ("random_poses_n", lambda: ak.calibration.random_poses(10**9, T, D),
     InvalidInputError, r"^n: "),
    ("plan_poses_candidates", lambda: ak.calibration.plan_poses(10, T, D, n_candidates=10**9),
     InvalidInputError, r"^n_candidates: "),
    ("synthetic_n", lambda: ak.calibration.synthetic_measurements(T, D, n=10**9),
     InvalidInputError, r"^n: "),
    ("random_configurations_n", lambda: ak.testing.random_configurations(10**9, D, rng=0),
     InvalidInputError, r"^n: "),
    ("sample_task_n", lambda: ak.synthesis.sample_task(_task(), 10**9),
     InvalidInputError, r"^n: "),
    ("reachability_samples", lambda: ak.synthesis.reachability(D, _task(), samples=10**8),
     InvalidInputError, r"^samples: "),
    ("evaluate_design_samples", lambda: ak.synthesis.evaluate_design(D, _task(), samples=10**7),
     InvalidInputError, r"^samples: "),
    ("certified_batch", lambda: ak.certified_forward_kinematics(
        np.zeros((200_000, 3)), T, D), InvalidInputError, r"^q, T_b_e: a batch of 200,000"),
    # --- raw exceptions ----------------------------------------------------------------
    ("from_toml_int", lambda: ak.Design.from_toml(3), TypeError, r"^path: "),
    ("from_toml_none", lambda: ak.Design.from_toml(None), TypeError, r"^path: "),
    ("load_npz_dev_zero", lambda: ak.analysis.load_npz("/dev/zero"), InvalidInputError,
     r"/dev/zero: .*device"),
    ("load_npz_dev_null", lambda: ak.analysis.load_npz("/dev/null"), InvalidInputError,
     r"/dev/null: .*device"),
    ("design_ragged_limits", lambda: ak.Design(l1=0.3, l2=0.1, l3=0.25, l4=0.15, l5=0.4,
                                               q_min=[[0, 0], [0]]),
     InvalidInputError, r"^q_min: "),
    ("serial_jacobian_batch", lambda: ak.analysis.serial_jacobian(np.empty(2), np.zeros((3, 5))),
     InvalidInputError, r"p \(2,\), u \(3,\)"),
    ("ups_transform_batch", lambda: ak.chain.ups_transform([], np.zeros((20, 5))),
     InvalidInputError, r"p \(0,\), u \(20,\)"),
    ("near_singular_list_name", lambda: ak.analysis.near_singular_configurations(
        ["auto"], [0.1], D), InvalidInputError, r"^name: "),
    ("check_measurements_empty_frame", lambda: ak.calibration.check_measurements(
        np.zeros((5, 3)), np.zeros((0, 4, 4)), D), InvalidInputError, r"^T_b_e: .*\(4, 4\)"),
    ("calibrate_nan_frame", lambda: ak.calibration.calibrate(
        np.tile(ak.robot.REFERENCE_Q, (10, 1)), np.zeros((10, 3)), _bad_frame(), D),
     InvalidInputError, r"^T_b_e: "),
    ("random_configurations_rng_str", lambda: ak.testing.random_configurations(3, D, rng="x"),
     TypeError, r"^rng: "),
    ("random_configurations_rng_float", lambda: ak.testing.random_configurations(
        3, D, rng=1.5), TypeError, r"^rng: "),
    ("sample_task_seed_float", lambda: ak.synthesis.sample_task(_task(), 5, seed=1.5),
     TypeError, r"^seed: "),
    ("circle_points_bad", lambda: ak.plot.circle_points([0, 0], False, n=11),
     InvalidInputError, r"^centre: "),
    ("save_view_dpi", lambda: ak.plot.save_view("/tmp/athenakin-never-written.png",
                                                dpi=10**9), InvalidInputError, r"^dpi: "),
    ("slot_statuses_str", lambda: ak.app.slot_statuses("0.1", [0] * 16), TypeError, r"^valid: "),
    ("slot_statuses_short", lambda: ak.app.slot_statuses([True] * 3, [0] * 16),
     InvalidInputError, r"^valid: "),
    ("angles_from_tip_batch", lambda: ak.app.angles_from_tip(np.zeros((2, 3))),
     InvalidInputError, r"^tip_e: "),
    ("message_html_int", lambda: ak.app.message_html(5, ""), TypeError, r"^text: "),
    ("message_html_level", lambda: ak.app.message_html("x", "loud"), ValueError, r"^level: "),
    ("forward_view_setup", lambda: ak.app.forward_view([], ak.robot.REFERENCE_Q), TypeError,
     r"^setup: "),
    ("slot_label_dict", lambda: ak.plot.slot_label({}), TypeError, r"^g: "),
    ("tip_from_angles_str", lambda: ak.app.tip_from_angles("a", 0.0, 0.1), TypeError,
     r"^azimuth: "),
    ("write_urdf_dev_full", lambda: ak.sim.write_urdf("/dev/full", T, D), InvalidInputError,
     r"^path: /dev/full is a device"),
    ("random_configurations_margin", lambda: ak.testing.random_configurations(
        3, D, rng=0, margin=1.5), InvalidInputError, r"^margin: "),
    ("cone_angle_nan", lambda: ak.plot.instrument_cone_path(10, T, cone_angle=np.nan),
     InvalidInputError, r"^cone_angle: "),
]


@pytest.mark.parametrize(("call", "exc", "match"), [r[1:] for r in RAISES],
                         ids=[r[0] for r in RAISES])
def test_a_bad_argument_is_a_named_error(call, exc, match):
    if "dev" in match and not os.path.exists("/dev/zero"):
        pytest.skip("no /dev devices on this platform")
    with pytest.raises(exc, match=match):
        call()


def test_playback_q_names_its_arguments():
    pb = ak.app.Playback(t=np.array([0.0, 1.0]), q=np.zeros((2, 3)), source="x")
    with pytest.raises(TypeError, match=r"^t: "):
        ak.app.playback_q(pb, [])
    with pytest.raises(TypeError, match=r"^pb: "):
        ak.app.playback_q(None, 0.0)


# --- values that were wrong or NaN and flagged valid ------------------------------------

def test_rcm_frame_from_a_huge_axis_is_a_rotation():
    F = ak.synthesis.rcm_frame_from_axis([0, 0, 0], [-1.0, -1.0, 1e300])
    np.testing.assert_allclose(np.linalg.det(F[:3, :3]), 1.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(F[:3, 0], [0, 0, 1], rtol=0, atol=1e-12)


@pytest.mark.parametrize("scale", [1e160, 1e300, 1e-300])
def test_study_conversions_of_huge_and_tiny_study_vectors(scale):
    X = ak.study.study_from_transform(T)
    np.testing.assert_allclose(ak.study.transform_from_study(X * scale), T, rtol=0, atol=1e-15)
    P = ak.study.paper_matrix_from_study(X * scale)
    np.testing.assert_allclose(P[1:, 0], T[:3, 3], rtol=0, atol=1e-15)
    R = ak.study.rotation_from_quaternion(X[:4] * scale)
    np.testing.assert_allclose(R, T[:3, :3], rtol=0, atol=1e-15)


def test_random_configurations_of_zero_is_empty():
    rc = ak.testing.random_configurations(0, D, rng=0)
    assert rc.q.shape == (0, 3) and rc.T_b_e.shape == (0, 4, 4) and rc.slot.shape == (0,)


def test_empty_batches_of_the_serial_chain():
    assert ak.chain.ups_transform([], np.zeros(5)).shape == (0, 4, 4)
    assert ak.analysis.serial_jacobian(np.empty(0), [0.1] * 5).shape == (0, 6, 6)


def test_xml_names_escape_markup_and_parse():
    for name in ['a<b>&"c\'', "ünï 設計"]:
        ET.fromstring(ak.sim.urdf_from_design(T, D, robot_name=name).split("-->", 1)[-1])
        root = ET.fromstring(ak.sim.mjcf_from_design(T, D, model_name=name).split("-->", 1)[-1])
        assert root.get("model") == name


# --- readers and writers of special files ------------------------------------------------

@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
@pytest.mark.parametrize("reader", [
    lambda p: ak.Design.from_toml(p),
    lambda p: ak.analysis.load_npz(p),
    lambda p: ak.synthesis.Task.from_toml(p),
    lambda p: ak.calibration.read_measurements_csv(p),
    lambda p: ak.motion.read_q_stream_csv(p),
    lambda p: ak.app.load_playback(p),
], ids=["design", "npz", "task", "measurements", "q_stream", "playback"])
def test_a_fifo_is_refused_without_blocking(tmp_path, reader):
    fifo = tmp_path / "in.fifo"
    os.mkfifo(fifo)
    with pytest.raises(ValueError, match="FIFO"):     # every reader's error is a ValueError
        reader(fifo)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
@pytest.mark.parametrize("writer", [
    lambda p: ak.sim.write_urdf(p, T, D),
    lambda p: ak.sim.write_mjcf(p, T, D),
    lambda p: ak.analysis.save_npz(p, ak.analysis.actuator_map(D, resolution=3)),
    lambda p: ak.plot.write_html(p, include_plotlyjs=False),
    lambda p: ak.plot.save_view(p, dpi=20),
], ids=["urdf", "mjcf", "npz", "html", "png"])
def test_a_writer_refuses_a_fifo(tmp_path, writer):
    fifo = tmp_path / "out.fifo"
    os.mkfifo(fifo)
    with pytest.raises(InvalidInputError, match=r"^path: .*FIFO"):
        writer(fifo)


def test_a_write_error_names_the_path(tmp_path):
    from athenakin._output import naming_path

    with pytest.raises(OSError) as info, naming_path(tmp_path / "x.urdf"):
        raise OSError(28, "No space left on device")
    assert info.value.filename == str(tmp_path / "x.urdf") and info.value.errno == 28


# --- subpackages as attributes -------------------------------------------------------------

@pytest.mark.parametrize("name", ["synthesis", "testing", "calibration", "app", "plot"])
def test_subpackages_are_attributes(name):
    code = f"import athenakin as ak; print(ak.{name}.__name__)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(REPO / "src")})
    assert r.returncode == 0 and r.stdout.strip() == f"athenakin.{name}", r.stderr


# --- the CLI: a closed pipe, Ctrl-C ---------------------------------------------------------

def _cli(*args: str, **kw):
    return subprocess.Popen([sys.executable, "-m", "athenakin", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE,
                            env={**os.environ, "PYTHONPATH": str(REPO / "src")}, **kw)


def test_fk_into_a_closed_pipe_exits_0_every_time():
    for _ in range(3):
        p = _cli("fk", "-0.1", "0.1", "0.45")
        p.stdout.readline()
        p.stdout.close()                  # head -1
        err = p.stderr.read().decode()
        p.stderr.close()
        # on a loaded machine, loading the kernels from the cache may take long enough for
        # the dispatch's notice (its only line on stderr); anything else is a fault
        err = "".join(ln for ln in err.splitlines(keepends=True)
                      if not ln.startswith("athenakin: compiling the numba kernels"))
        assert p.wait(timeout=120) == 0 and err == ""


def test_ctrl_c_while_the_cli_imports_is_one_line_and_130():
    # the hook the package installs when the process is the CLI (argv[0] 'athenakin' or
    # '-m'): an interrupt before cli.main can catch it
    code = ("import sys; sys.argv = ['/usr/bin/athenakin']; import athenakin; "
            "raise KeyboardInterrupt")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(REPO / "src")})
    assert r.returncode == 130 and r.stderr == "athenakin: interrupted (no output written)\n"


def test_a_library_import_leaves_the_excepthook_alone():
    code = "import sys, athenakin; print(sys.excepthook is sys.__excepthook__)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(REPO / "src")})
    assert r.stdout.strip() == "True", r.stderr


def test_ctrl_c_in_synthesize_names_the_resumable_folder(tmp_path, monkeypatch, capsys):
    import athenakin.synthesis as syn
    from athenakin.cli import main

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(syn, "evaluate", interrupted)
    task = REPO / "examples" / "synthesis" / "task_pancreas.toml"
    out = tmp_path / "study.parquet"
    assert main(["synthesize", str(task), "-o", str(out), "--no-figures"]) == 130
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "interrupted" in err and str(out) in err and "resume" in err


# --- the correctness audit: near tangency, degeneracy thresholds, both backends --------------

def _backends():
    from athenakin._dispatch import numba_available

    return ["numpy", "numba"] if numba_available() else ["numpy"]


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_near_tangent_slots_are_within_their_bound_or_flagged(backend):
    if backend not in _backends():
        pytest.skip("numba not installed")
    g = ak.parallel.circle_geometry(np.array([-0.1, 0.1, 0.3]), D)
    q3_t = float(g["d"] - g["r1"])                     # inner tangency
    offsets = np.array([0.0, 1e-16, -1e-16, 1e-15, -1e-15, 1e-14, 1e-13, 1e-12, 1e-11, 1e-10])
    q = np.stack([np.full(offsets.size, -0.1), np.full(offsets.size, 0.1), q3_t + offsets], -1)
    for closure_tol in (1e-9, 1e-7, 1e-6):
        sol = ak.forward_kinematics(q, T, D, errors="flag", backend=backend,
                                    closure_tol=closure_tol)
        assert np.all(sol.residual[sol.valid] <= closure_tol)      # valid: within the bound
        bad = ~sol.valid & (sol.reason != 0)
        assert np.all(bad == ~sol.valid)
    sol = ak.forward_kinematics(q, T, D, errors="flag", backend=backend)
    assert np.all(sol.reason[:3] == ak.Reason.CIRCLES_TANGENT)     # at tangency to 1e-16 m
    assert np.all(sol.valid[-1])                                   # 1e-10 m away: 16 solutions


def test_near_tangent_residual_bounds_the_true_offset():
    # mode +1 merged at the default tangent_tol against the true intersection (tol 0)
    g = ak.parallel.circle_geometry(np.array([-0.1, 0.1, 0.3]), D)
    q3 = float(g["d"] - g["r1"]) + np.array([1e-16, 1e-15, 1e-14, 1e-13])
    q = np.stack([np.full(4, -0.1), np.full(4, 0.1), q3], axis=-1)
    merged = ak.parallel.parallel_forward_kinematics(q, D)
    true = ak.parallel.parallel_forward_kinematics(q, D, tangent_tol=0.0)
    ok = true.valid[:, 0]
    off = np.linalg.norm(merged.O_s[ok, 0] - true.O_s[ok, 0], axis=-1)
    assert np.all(off <= merged.residual[ok, 0])


@pytest.mark.parametrize("kind", ["u2", "u4", "p"])
@pytest.mark.parametrize("spread", [1e-3, 1e-6, 1e-9])
@pytest.mark.parametrize("tol", [None, 1e-6])
def test_backends_classify_alike_at_the_degeneracy_thresholds(kind, spread, tol):
    """|sin u2|, |sin u4| or |p| within ``spread`` (relative) of the threshold: numba and
    numpy flag exactly the same slots (they once disagreed on up to half the items)."""
    if "numba" not in _backends():
        pytest.skip("numba not installed")
    thr = 1e-12 if tol is None else tol
    rc = ak.testing.random_configurations(200, D, rng=5)
    rng = np.random.default_rng(1)
    f = thr * (1.0 + rng.uniform(-spread, spread, 200))
    u, p = rc.u.copy(), rc.p.copy()
    if kind == "u2":
        u[:, 1] = np.arcsin(f) * np.sign(np.sin(u[:, 1]))
    elif kind == "u4":
        u[:, 3] = np.arcsin(f)
    else:
        p = f * np.sign(p)
    T_b_e = rc.T_b_s @ ak.chain.ups_transform(p, u)
    kw = {} if tol is None else ({"p_zero_tol": tol} if kind == "p" else {"degenerate_tol": tol})
    a = ak.forward_kinematics(rc.q, T_b_e, D, errors="flag", backend="numpy", **kw)
    b = ak.forward_kinematics(rc.q, T_b_e, D, errors="flag", backend="numba", **kw)
    np.testing.assert_array_equal(a.reason, b.reason)
    np.testing.assert_array_equal(a.item_reason, b.item_reason)
    flagged = {"u2": ak.Reason.UJOINT_SINGULAR, "u4": ak.Reason.WRIST_SINGULAR,
               "p": ak.Reason.SERIAL_P_ZERO}[kind]
    assert np.any(a.reason == flagged) and np.any(a.valid)     # both sides of the threshold


# --- the skip policy of tests/conftest.py ----------------------------------------------------

@pytest.mark.parametrize(("reason", "expected_unexpected"), [
    ("because I felt like it", True),
    ("could not import 'athenakin_no_such_module': No module named ...", False),
    ("could not import 'numpy': numpy is broken", True),         # numpy imports here
    ("needs the 'app' extra (athenakin_no_such_module)", False),
    ("no FIFOs on this platform", hasattr(os, "mkfifo")),
    ("no /dev devices on this platform", os.path.exists("/dev/zero")),
    ("needs Python >= 3.0", True),                                   # this Python is newer
    ("needs Python >= 99.0", False),
])
def test_the_skip_allow_list(reason, expected_unexpected):
    from conftest import unexpected

    assert unexpected(reason) is expected_unexpected


def test_a_gpu_skip_is_allowed_only_without_a_gpu():
    from conftest import _has_gpu, unexpected

    assert unexpected("needs a GPU") is _has_gpu()


def test_a_numba_skip_is_unexpected_where_numba_runs():
    from conftest import unexpected

    assert unexpected("numba not available here") is ("numba" in _backends())


@pytest.mark.parametrize("errors", ["flag", "raise"])
def test_numpy_fk_in_blocks_equals_one_block(monkeypatch, errors):
    """A large batch is computed in blocks of FK_BLOCK poses (bounded memory), same result."""
    from athenakin.robot import _fk

    rc = ak.testing.random_configurations(50, D, rng=3)
    q = rc.q.reshape(5, 10, 3)
    Tb = rc.T_b_e.reshape(5, 10, 4, 4)
    whole = ak.forward_kinematics(q, Tb, D, backend="numpy", errors=errors)
    monkeypatch.setattr(_fk, "FK_BLOCK", 7)
    blocks = ak.forward_kinematics(q, Tb, D, backend="numpy", errors=errors)
    for k, v in vars(whole).items():
        if isinstance(v, np.ndarray):
            np.testing.assert_array_equal(vars(blocks)[k], v, err_msg=k)
    bad = q.copy()
    bad[3, 4] = [-0.1, 0.1, 0.2]                       # circles apart
    with pytest.raises(ak.OutOfWorkspaceError, match=r"\(3, 4\)"):
        ak.forward_kinematics(bad, Tb, D, backend="numpy", errors="raise")
    sub = ak.forward_kinematics(q, Tb, D, backend="numpy", fields=("valid",))
    np.testing.assert_array_equal(sub.valid, whole.valid)


# --- the audit cannot overstate ---------------------------------------------------------------

def _audit_module():
    import importlib.util

    if "audit_api" in sys.modules:
        return sys.modules["audit_api"]
    spec = importlib.util.spec_from_file_location("audit_api", REPO / "scripts" / "audit_api.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["audit_api"] = mod              # dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize(("msg", "names", "named"), [
    ("math domain error in sqrt", ("q",), False),                  # 'q' inside 'sqrt'
    ("operands could not be broadcast together with shapes (2,) (3,)", ("shape",), False),
    ("q: expected shape (..., 3), got shape (2,)", ("q",), True),
    ("p, u: batch shapes p (0,), u (20,)", ("u",), True),
    ("tangent_tol: expected a tolerance in [0, 0.001]", ("tol",), False),
    ("tangent_tol: expected a tolerance in [0, 0.001]", ("tangent_tol",), True),
])
def test_the_audit_matches_argument_names_as_whole_tokens(msg, names, named):
    assert _audit_module().names_argument(msg, names) is named


def test_the_audit_has_no_time_budget_and_requires_generators():
    import inspect

    audit = _audit_module()
    assert "budget_s" not in inspect.signature(audit.fuzz_function).parameters
    assert "no_generator" in audit.FINDINGS
    for sub in ("plot", "app", "testing", "calibration", "synthesis"):
        assert sub in audit.SUBPACKAGES

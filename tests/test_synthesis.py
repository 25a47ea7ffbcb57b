"""athenakin.synthesis: the task, its samples, the metrics against the analysis module."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin.errors import InvalidInputError
from athenakin.synthesis import (
    METRIC_COLUMNS,
    StudyOptions,
    Task,
    TaskFileError,
    evaluate_design,
    rcm_frame_from_axis,
    reachability,
    sample_task,
)

REF = ak.Design.default()
T_REF = ak.default_rcm_frame(REF)


def _task(**kw: object) -> Task:
    args: dict[str, object] = {"rcm": T_REF[:3, 3], "axis": T_REF[:3, 0], "half_angle": 0.45,
                               "depth": (0.2, 0.3)}
    args.update(kw)
    return Task(**args)  # type: ignore[arg-type]


@pytest.mark.parametrize(("kw", "match"), [
    ({"axis": [0.0, 0.0, 2.0]}, "expected a unit vector"),
    ({"axis": [0.0, 0.0]}, r"expected shape \(3,\)"),
    ({"half_angle": 0.0}, r"half_angle: expected a value in \(0, pi/2\]"),
    ({"half_angle": 1.6}, r"half_angle: expected a value in \(0, pi/2\]"),
    ({"half_angle": math.nan}, "half_angle: expected a finite number"),
    ({"depth": (0.3, 0.2)}, "0 <= d_min <= d_max"),
    ({"depth": (-0.1, 0.2)}, "0 <= d_min <= d_max"),
    ({"depth": (0.1,)}, r"expected \(d_min, d_max\)"),
    ({"rcm": [0.0, np.inf, 0.0]}, "rcm: expected finite numbers"),
])
def test_task_rejects_bad_values(kw: dict[str, object], match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        _task(**kw)


def test_task_edge_values_accepted() -> None:
    t = _task(half_angle=math.pi / 2, depth=(0.0, 0.0))
    assert t.half_angle == math.pi / 2 and t.depth == (0.0, 0.0)
    assert_allclose(t.solid_angle, 2 * math.pi, rtol=0, atol=1e-15)


def test_task_toml_round_trip(tmp_path) -> None:
    t = _task(name="port 1")
    p = tmp_path / "t.toml"
    p.write_text(t.to_toml())
    assert Task.from_toml(p) == t


def test_example_task_file_loads() -> None:
    from pathlib import Path

    t = Task.from_toml(Path(__file__).parents[1] / "examples/synthesis/task_pancreas.toml")
    assert_allclose(t.half_angle, math.radians(25.0), rtol=0, atol=1e-15)
    assert_allclose(t.T_b_e, T_REF, rtol=0, atol=1e-6)


@pytest.mark.parametrize(("text", "match"), [
    ("[task\nrcm = 1", "not valid TOML"),
    ("[task]\nrcm = [0, 0, 0]\naxis = [0, 0, 1]\ndepth = [0.1, 0.2]", "missing half_angle"),
    ("[task]\nrcm = [0, 0, 0]\naxis = [0, 0, 1]\nhalf_angle = 0.3\nhalf_angle_deg = 20\n"
     "depth = [0.1, 0.2]", "exactly one"),
    ("[task]\nrcm = [0, 0, 0]\naxis = [0, 0, 1]\nhalf_angle = 0.3\ndepth = [0.1, 0.2]\n"
     "colour = 1", "unknown key"),
    ("[task]\nrcm = [0, 0]\naxis = [0, 0, 1]\nhalf_angle = 0.3\ndepth = [0.1, 0.2]",
     r"rcm: expected shape \(3,\)"),
    ("[task]\nrcm = [0, 0, 0]\naxis = [0, 0, 0]\nhalf_angle = 0.3\ndepth = [0.1, 0.2]",
     "non-zero"),
    ("[task]\nrcm = [0, 0, 0]\naxis = [0, 0, 1]\nhalf_angle = 'wide'\ndepth = [0.1, 0.2]",
     "half_angle: expected a real number"),
])
def test_malformed_task_file_is_one_line_named_error(tmp_path, text: str, match: str) -> None:
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(TaskFileError, match=match) as exc:
        Task.from_toml(p)
    assert "\n" not in str(exc.value) and str(p) in str(exc.value)


def test_missing_task_file() -> None:
    with pytest.raises(TaskFileError, match="cannot read the task file"):
        Task.from_toml("/nonexistent/task.toml")


def test_rcm_frame_is_the_reference_construction() -> None:
    assert_allclose(rcm_frame_from_axis(T_REF[:3, 3], T_REF[:3, 0]), T_REF, rtol=0, atol=1e-14)
    T = rcm_frame_from_axis([0, 0, 0], [1.0, 0, 0])        # axis along the rail: fallback
    assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), rtol=0, atol=1e-15)
    assert_allclose(T[:3, 0], [1, 0, 0], rtol=0, atol=0)


def test_samples_uniform_over_cone_and_depth() -> None:
    t = _task(half_angle=0.6, depth=(0.1, 0.25))
    s = sample_task(t, 200_000, seed=2)
    assert_allclose(np.linalg.norm(s.direction_e, axis=1), 1.0, rtol=0, atol=1e-15)
    cos_t = s.direction_e[:, 0]                             # cone axis is x_e
    assert np.all(cos_t >= math.cos(0.6) - 1e-15)
    assert np.all((s.depth >= 0.1) & (s.depth <= 0.25))
    # uniform in solid angle: cos(theta) uniform on [cos a, 1]; depth uniform
    n = len(cos_t)
    assert abs(cos_t.mean() - (1 + math.cos(0.6)) / 2) < 5 * (1 - math.cos(0.6)) / math.sqrt(
        12 * n)
    hist, _ = np.histogram(cos_t, bins=10)
    assert np.all(np.abs(hist / (n / 10) - 1) < 0.03)
    hist, _ = np.histogram(s.phi, bins=8, range=(0, 2 * math.pi))
    assert np.all(np.abs(hist / (n / 8) - 1) < 0.03)
    assert abs(s.depth.mean() - 0.175) < 5 * 0.15 / math.sqrt(12 * n)
    s2 = sample_task(t, 200_000, seed=2)
    assert np.array_equal(s.direction_e, s2.direction_e) and np.array_equal(s.depth, s2.depth)


def test_tip_and_o_s_follow_the_task_definition() -> None:
    """tip = rcm + depth d and O_s = rcm - (L - depth) d: both IK forms give the same q."""
    t = _task()
    s, q, mode, _ = reachability(REF, t, samples=3000, seed=1)
    ok = mode != 0
    assert 0.3 < ok.mean() < 1.0
    q_tip, res = ak.q_from_tool_tip(t.T_b_e, s.depth[:, None] * s.direction_e, REF,
                                    errors="flag", backend="numpy")
    assert np.array_equal(res.valid, ok)
    assert_allclose(q_tip[ok], q[ok], rtol=0, atol=1e-12)
    d_b = s.direction_e[ok] @ t.T_b_e[:3, :3].T
    assert_allclose(res.O_s[ok], t.rcm - (REF.tool_length - s.depth[ok])[:, None] * d_b,
                    rtol=0, atol=1e-15)


@pytest.fixture(scope="module")
def brute() -> dict[str, object]:
    """Every metric recomputed sample by sample with the analysis module."""
    t = _task(half_angle=0.6, depth=(0.18, 0.32))
    n, seed, res = 3000, 4, 2e-6
    s, q, mode, _ = reachability(REF, t, samples=n, seed=seed, backend="numpy")
    ok = mode != 0
    qv, mv = q[ok], mode[ok]
    rep = ak.analysis.singularities(qv, t.T_b_e, REF, mode=mv, jacobians=False)
    J = ak.analysis.tool_tip_jacobian(qv, t.T_b_e, REF, mode=mv, backend="numpy")
    Jp = ak.analysis.parallel_jacobian(qv, REF, mode=mv, backend="numpy")
    corners = np.array([c for c in itertools.product((1.0, -1.0), repeat=3)])
    err = res * np.max(np.linalg.norm(np.einsum("nij,kj->nki", J, corners), axis=-1), axis=-1)
    return {"task": t, "n": n, "seed": seed, "res": res, "ok": ok, "q": qv, "mode": mv,
            "rep": rep, "cond_tip": ak.analysis.condition_number(J),
            "cond_par": ak.analysis.condition_number(Jp), "err": err,
            "m": evaluate_design(REF, t, samples=n, seed=seed, encoder_resolution=res)}


def test_metrics_match_the_analysis_module(brute: dict[str, object]) -> None:
    m, ok, rep = brute["m"], brute["ok"], brute["rep"]
    assert isinstance(m, dict) and set(m) == set(METRIC_COLUMNS)
    assert m["coverage"] == ok.mean()
    modes = brute["mode"]
    assert m["coverage_plus"] == np.count_nonzero(modes == 1) / brute["n"]
    assert m["coverage_mode"] == max(m["coverage_plus"], m["coverage_minus"])
    for name, cond in rep.conditions.items():
        # q here from the numpy IK, in evaluate_design from the compiled one (1e-16 apart)
        assert_allclose(m[f"margin_{name}"], np.min(cond.value), rtol=1e-9, atol=1e-15,
                        err_msg=name)
    assert_allclose(m["cond_tip_max"], np.max(brute["cond_tip"]), rtol=1e-9, atol=0)
    assert_allclose(m["cond_parallel_max"], np.max(brute["cond_par"]), rtol=1e-9, atol=0)
    assert_allclose(m["tip_error_max"], np.max(brute["err"]), rtol=1e-9, atol=0)
    assert_allclose(m["tip_error_mean"], np.mean(brute["err"]), rtol=1e-9, atol=0)
    q, lo, hi = brute["q"], REF.stroke_min, REF.stroke_max
    for i in range(3):
        assert_allclose(m[f"stroke_use_q{i + 1}"], np.ptp(q[:, i]) / (hi[i] - lo[i]),
                        rtol=1e-9, atol=0)
    assert m["size"] == pytest.approx(2 * 0.30 + 2 * 0.25 + 0.10 + 0.15 + 0.40 + 0.4 + 0.4 + 0.5,
                                      abs=1e-12)


@pytest.mark.skipif(not ak._backend.numba_available(), reason="numba not available here")
def test_metrics_numba_and_numpy_ik_agree(brute: dict[str, object]) -> None:
    t = brute["task"]
    _, q1, m1, r1 = reachability(REF, t, samples=3000, seed=4, backend="numba")
    _, q2, m2, r2 = reachability(REF, t, samples=3000, seed=4, backend="numpy")
    assert np.array_equal(m1, m2) and np.array_equal(r1, r2)
    assert_allclose(q1, q2, rtol=0, atol=1e-12, equal_nan=True)


def test_unreachable_task_gives_zero_coverage_and_nan_metrics() -> None:
    t = Task(rcm=[0.0, 2.0, 2.0], axis=[0.0, 0.0, -1.0], half_angle=0.2, depth=(0.1, 0.2))
    m = evaluate_design(REF, t, samples=500, seed=0)
    assert m["coverage"] == 0 and m["coverage_mode"] == 0
    assert math.isnan(m["margin_min"]) and math.isnan(m["tip_error_max"])
    assert m["size"] > 0


def test_invalid_designs_are_flagged_rows_not_an_abort() -> None:
    pd = pytest.importorskip("pandas")
    pytest.importorskip("dask")
    from athenakin.synthesis import evaluate, row_from_design

    good = row_from_design(REF)
    rows = [REF, dict(good, l3=-0.25), dict(good, q1_min=0.2),
            dict(good, q3_min=0.01, q3_max=0.02), dict(good, l1="long")]
    df = evaluate(rows, _task(), samples=400, seed=0, scheduler="synchronous",
                  options=StudyOptions(progress=False))
    assert isinstance(df, pd.DataFrame) and list(df["design"]) == [0, 1, 2, 3, 4]
    assert df["valid"].tolist() == [True, False, False, False, False]
    assert "l3: expected a positive number" in df["reason"][1]
    assert "q_min <= q_max" in df["reason"][2]
    assert "strokes cannot assemble" in df["reason"][3]
    assert "l1" in df["reason"][4]
    assert df["reason"][0] == "" and 0 < df["coverage"][0] <= 1
    assert df.loc[1:, "coverage"].isna().all()


def test_pareto_mask_table() -> None:
    from athenakin.synthesis import pareto_mask

    F = np.array([[1.0, 5.0], [2.0, 2.0], [3.0, 3.0], [5.0, 1.0], [2.0, 2.0], [np.nan, 0.0]])
    assert pareto_mask(F).tolist() == [True, True, False, True, True, False]


def test_bounds_checked_by_name() -> None:
    from athenakin.synthesis import check_bounds, default_bounds

    b = default_bounds(REF)
    assert check_bounds(b) == b and b["l1"] == pytest.approx((0.225, 0.375))
    with pytest.raises(InvalidInputError, match=r"missing \['q3_max'\]"):
        check_bounds({k: v for k, v in b.items() if k != "q3_max"})
    with pytest.raises(InvalidInputError, match="bounds.l2: expected finite lo <= hi"):
        check_bounds(dict(b, l2=(0.2, 0.1)))


def test_optimize_places_the_reference_on_the_front() -> None:
    pytest.importorskip("pymoo")
    pytest.importorskip("dask")
    from athenakin.synthesis import optimize, pareto_mask

    r = optimize(_task(), population=8, generations=2, samples=600, seed=3,
                 scheduler="synchronous")
    assert len(r.table) == 1 + 8 * 2 and r.table["generation"].iloc[0] == -1
    assert r.reference["name"] == REF.name
    F = np.stack([-r.front["coverage_mode"], r.front["size"], r.front["tip_error_max"]], -1)
    assert pareto_mask(F).all() and r.front["valid"].all()
    # gains are real improvements of designs that dominate the reference
    if r.dominating:
        assert r.gains["coverage_mode"] >= 0 and r.gains["size"] >= 0
        assert not r.reference_on_front


EXAMPLE = str(__import__("pathlib").Path(__file__).parents[1]
              / "examples/synthesis/task_pancreas.toml")


def test_cli_synthesize_locally_with_figures(tmp_path, capsys) -> None:
    pytest.importorskip("dask")
    pytest.importorskip("matplotlib")
    from athenakin.cli import main

    out = tmp_path / "r.parquet"
    rc = main(["synthesize", EXAMPLE, "--designs", "3", "--samples", "500", "-o", str(out),
               "--scheduler", "synchronous"])
    text = capsys.readouterr().out
    assert rc == 0 and "4 designs" in text and "cov. 1 mode" in text
    assert "design 0: the reference design" in text             # the table's caption
    for name in ("pareto.png", "parameters.png", "coverage.png"):
        assert (tmp_path / "r.parquet-figures" / name).stat().st_size > 1000
    from athenakin.synthesis import read_study

    df = read_study(out)
    assert len(df) == 4 and df["name"][0] == REF.name


def test_cli_bad_task_file_is_one_line(tmp_path, capsys) -> None:
    from athenakin.cli import main

    p = tmp_path / "t.toml"
    p.write_text("[task]\nrcm = [0, 0, 0]\n")
    assert main(["synthesize", str(p), "-o", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "TaskFileError" in err and "missing axis" in err


def test_docstring_examples_of_the_task_module() -> None:
    import doctest

    import athenakin.synthesis._task as mod

    assert doctest.testmod(mod, optionflags=doctest.ELLIPSIS).failed == 0


def test_cli_optimize_json(tmp_path, capsys) -> None:
    pytest.importorskip("pymoo")
    import json

    from athenakin.cli import main

    out = tmp_path / "s.parquet"
    args = ["synthesize", EXAMPLE, "--optimize", "--population", "4", "--generations", "1",
            "--samples", "300", "--scheduler", "synchronous", "-o", str(out), "--no-figures"]
    assert main([*args, "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["designs"] == 5 and rep["front"] and set(rep["trade_offs"]) == {
        "coverage_mode", "size", "tip_error_max"}
    assert isinstance(rep["reference_on_front"], bool)
    assert main(args) == 1                                     # the folder is not empty now
    assert "FileExistsError" in capsys.readouterr().err


def test_mapping_without_strokes_is_an_unlimited_design_in_the_table() -> None:
    pytest.importorskip("dask")
    from athenakin.synthesis import evaluate

    row = {"l1": 0.3, "l2": 0.1, "l3": 0.25, "l4": 0.15, "l5": 0.4, "name": math.nan}
    df = evaluate([row], _task(), samples=300, seed=0, scheduler="synchronous",
                  options=StudyOptions(progress=False))
    r = df.iloc[0]
    assert r["valid"] and r["name"] == "" and r["tool_length"] == REF.tool_length
    assert r["q1_min"] == -math.inf and r["q3_max"] == math.inf and r["size"] == math.inf
    assert r["stroke_use_q1"] == 0.0 and r["coverage"] > 0


def test_audit_arguments_named() -> None:
    """Audit of issue 13: designs, tasks, counts and matrices of the synthesis API were
    AttributeError / TypeError / numpy tracebacks; each now names its argument."""
    d = ak.Design.default()
    task = ak.synthesis.Task(rcm=np.array([0.0, 0.3, 0.1]), axis=np.array([0.0, 0.0, -1.0]),
                             half_angle=0.3, depth=(0.05, 0.1))
    with pytest.raises(TypeError, match="design"):
        ak.synthesis.row_from_design(None)
    with pytest.raises(TypeError, match="design"):
        ak.synthesis.default_bounds(float("nan"))
    with pytest.raises(TypeError, match="spread"):
        ak.synthesis.default_bounds(d, spread=None)
    with pytest.raises(TypeError, match="design"):
        ak.synthesis.evaluate_design(None, task, samples=10)
    with pytest.raises(TypeError, match="task"):
        ak.synthesis.reachability(d, [[1, 2]], samples=10)
    with pytest.raises(InvalidInputError, match="samples"):
        ak.synthesis.reachability(d, task, samples=10**400)
    with pytest.raises((TypeError, ValueError), match="F"):
        ak.synthesis.pareto_mask(None)
    with pytest.raises(TypeError, match="row"):
        ak.synthesis.design_from_row(None)
    with pytest.raises(InvalidInputError, match="rcm"):
        ak.synthesis.rcm_frame_from_axis([10**400, 0, 0], [0, 0, 1.0])


def test_audit_study_arguments_named(tmp_path) -> None:
    """Audit of issue 13: optimize(reference=nan, generations=1e308), evaluate(out=nan,
    on_chunk=nan) and design_rows(0-d array) named the wrong argument or none."""
    pytest.importorskip("pandas")
    task = ak.synthesis.Task(rcm=np.array([0.0, 0.3, 0.1]), axis=np.array([0.0, 0.0, -1.0]),
                             half_angle=0.3, depth=(0.05, 0.1))
    with pytest.raises(TypeError, match="reference"):
        ak.synthesis.optimize(task, reference=float("nan"))
    with pytest.raises(InvalidInputError, match="generations"):
        ak.synthesis.optimize(task, generations=1e308)
    with pytest.raises(TypeError, match="out"):
        ak.synthesis.evaluate([ak.Design.default()], task, samples=10, out=float("nan"))
    with pytest.raises(TypeError, match="on_chunk"):
        ak.synthesis.evaluate([ak.Design.default()], task, samples=10, on_chunk=1.0)
    with pytest.raises(TypeError, match="designs"):
        ak.synthesis.design_rows(np.array(1.0))

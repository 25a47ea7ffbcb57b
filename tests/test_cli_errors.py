"""Every CLI failure is one line on stderr and a non-zero exit (issue 13.11, issue 12.6).

The inputs that used to end in a traceback, an exhausted memory or a silent
wrong answer; resource limits are checked before any work.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from athenakin.cli import main


def _one_line_error(capsys, code: int, *, want: str = "") -> str:
    err = capsys.readouterr().err
    assert code == 1, err
    assert "Traceback" not in err and err.count("\n") == 1 and err.startswith("athenakin "), err
    assert want in err, err
    return err


@pytest.fixture
def files(tmp_path: Path) -> dict[str, Path]:
    deep_json = tmp_path / "deep.json"
    deep_json.write_text('{"T_b_e": ' + "[" * 50_000 + "]" * 50_000 + "}")
    deep_toml = tmp_path / "deep.toml"
    deep_toml.write_text("a = " + "[" * 50_000 + "]" * 50_000 + "\n")
    huge = tmp_path / "huge.toml"
    huge.write_text("[design]\nl1 = 1e200\nl2 = 0.1\nl3 = 0.25\nl4 = 0.15\nl5 = 0.4\n")
    bom = tmp_path / "bom.csv"
    bom.write_text("x_m,y_m,z_m\n0.25,0,0\n0.26,-0.01,0\n", encoding="utf-8-sig")
    bom_q = tmp_path / "bom_q.csv"
    bom_q.write_text("t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n0.01,-0.1,0.1,0.451\n",
                     encoding="utf-8-sig")
    return {"deep_json": deep_json, "deep_toml": deep_toml, "huge": huge, "bom": bom,
            "bom_q": bom_q, "tmp": tmp_path}


def test_deeply_nested_json_and_toml_are_one_line_errors(files, capsys):
    code = main(["fk", "-0.1", "0.1", "0.45", "--rcm-file", str(files["deep_json"])])
    _one_line_error(capsys, code, want="nested too deeply")
    code = main(["fk", "-0.1", "0.1", "0.45", "--design", str(files["deep_toml"])])
    _one_line_error(capsys, code, want="nested too deeply")


@pytest.mark.parametrize("argv", [
    ["fk", "-0.1", "0.1", "0.45"],
    ["ik", "--tip", "0.25", "0", "0"],
    ["singularities", "-0.1", "0.1", "0.45", "--no-files"],
])
def test_overflow_designs_are_one_line_errors(files, capsys, argv):
    code = main([*argv, "--design", str(files["huge"])])
    _one_line_error(capsys, code)


@pytest.mark.parametrize("argv,want", [
    (["animate", "-o", "{tmp}/a.gif", "--fps", "0", "--no-progress"], "--fps"),
    (["animate", "-o", "{tmp}/a.gif", "--fps", "1e9", "--no-progress"], "--fps"),
    (["animate", "-o", "{tmp}/a.gif", "--frames", "100000000", "--no-progress"], "--frames"),
    (["view", "-o", "{tmp}/v.png", "--dpi", "20000"], "--dpi"),
    (["workspace", "--resolution", "3000", "--out", "{tmp}/ws"], "--resolution"),
    (["workspace", "--cone-resolution", "1000", "1000", "1000", "--no-files"],
     "--cone-resolution"),
    (["singularities", "--resolution", "100000", "--no-figures", "--out", "{tmp}/s"],
     "--resolution"),
    (["singularities", "nan", "0", "0.45", "--no-files"], "finite"),
    (["singularities", "-0.1", "0.1", "0.45", "--tol", "nan", "--no-files"], "--tol"),
    (["export", "-o", "{tmp}/m.xml", "--check", "100000000"], "--check"),
    (["view", "nan", "0.1", "0.45", "-o", "{tmp}/v.png"], "finite"),
    (["fk", "-0.1", "0.1", "0.45", "--rcm", "nan", "0", "0", "0", "0", "0"], "--rcm"),
])
def test_resource_limits_and_non_finite_values_are_checked_up_front(files, capsys, argv, want):
    code = main([a.format(tmp=files["tmp"]) for a in argv])
    _one_line_error(capsys, code, want=want)
    assert sorted(p.name for p in files["tmp"].iterdir()) == sorted(
        ["deep.json", "deep.toml", "huge.toml", "bom.csv", "bom_q.csv"])


def test_plan_reads_a_csv_with_a_byte_order_mark(files, capsys):
    out = files["tmp"] / "t.csv"
    assert main(["plan", str(files["bom"]), "-o", str(out), "--no-plots"]) == 0
    assert out.read_text().startswith("t_s,")


def test_track_keeps_the_time_column_of_a_csv_with_a_byte_order_mark(files):
    from athenakin.motion import read_q_stream_csv

    q, t = read_q_stream_csv(files["bom_q"])
    assert t is not None and t.tolist() == [0.0, 0.01] and q.shape == (2, 3)


def test_fk_with_two_values_says_three_actuator_values_are_expected(capsys):
    with pytest.raises(SystemExit) as e:
        main(["fk", "-0.1", "0.1"])
    assert e.value.code == 2
    assert "three actuator values q1 q2 q3 (m)" in capsys.readouterr().err


def test_ik_refuses_p_with_tip(capsys):
    code = main(["ik", "--tip", "0.25", "0", "0", "--p", "0.2"])
    _one_line_error(capsys, code, want="--p goes with --direction only")
    code = main(["ik", "--u345", "10", "80", "0", "--p", "0.2"])
    _one_line_error(capsys, code, want="--p")


def test_runtime_warnings_do_not_leak(capsys):
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        main(["fk", "1e300", "0", "0.45"])
    assert not [w for w in rec if issubclass(w.category, RuntimeWarning)]
    assert "Warning" not in capsys.readouterr().err


def test_debug_shows_the_traceback(capsys):
    with pytest.raises(ValueError, match="--p goes with"):
        main(["--debug", "ik", "--tip", "0.25", "0", "0", "--p", "0.2"])


def test_unexpected_errors_are_one_line_with_exit_code_70(monkeypatch, capsys):
    import athenakin.cli._demo as demo

    def bug(args):
        raise KeyError("oops")

    monkeypatch.setattr(demo, "run", bug)
    assert main(["demo"]) == 70
    err = capsys.readouterr().err
    assert "internal error" in err and "--debug" in err and err.count("\n") == 1


def test_animate_says_when_it_subsampled_and_why_the_video_is_longer(tmp_path, capsys,
                                                                     monkeypatch):
    import athenakin.plot as plot

    seen = {}

    def fake_animate(path, q, T, design, *, fps, **kw):   # the rendering is tested elsewhere
        seen.update(frames=len(q), fps=fps)
        Path(path).write_bytes(b"GIF89a")

    monkeypatch.setattr(plot, "animate", fake_animate)
    rows = "\n".join(f"{0.001 * i:.3f},-0.1,0.1,{0.45 + 1e-5 * i:.6f}" for i in range(4180))
    src = tmp_path / "traj.csv"
    src.write_text("t_s,q1_m,q2_m,q3_m\n" + rows + "\n")
    out = tmp_path / "a.gif"
    assert main(["animate", "-o", str(out), "--q-file", str(src), "--no-progress",
                 "--fps", "15"]) == 0
    text = capsys.readouterr().out
    assert "120 of 4180 rows" in text
    assert "the video lasts 7.93 s" in text and "4.18 s motion" in text
    # without --fps the video plays the motion in its own time (at most 50 fps)
    out2 = tmp_path / "b.gif"
    assert main(["animate", "-o", str(out2), "--q-file", str(src), "--no-progress",
                 "--frames", "40"]) == 0
    text = capsys.readouterr().out
    assert "40 of 4180 rows" in text and "video lasts" not in text
    assert seen["frames"] == 40 and abs(39 / seen["fps"] - 4.179) < 1e-9


def test_python_dash_m_athenakin_runs():
    r = subprocess.run([sys.executable, "-m", "athenakin", "fk", "-0.1", "0.1", "0.45",
                        "--json"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and json.loads(r.stdout)["n_solutions"] == 16


def test_a_closed_pipe_ends_quietly():
    """``athenakin demo | head -1``: no 'BrokenPipeError' on stderr, and exit 0 (issue 23:
    whether the output fitted the pipe before the reader left is a race; the exit code
    must not depend on it)."""
    p = subprocess.Popen([sys.executable, "-m", "athenakin", "demo"], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE)
    p.stdout.close()                      # the reader is gone before anything is written
    err = p.stderr.read().decode()
    p.wait(timeout=120)
    p.stderr.close()
    # the demo calls the compiled public functions: on a busy machine the first call may
    # print the one-line notice that numba loads its kernels; nothing else may appear
    err = "".join(line for line in err.splitlines(keepends=True)
                  if not line.startswith("athenakin: compiling the numba kernels"))
    assert err == "" and p.returncode == 0


# --- findings of the CLI audit (scripts/audit_cli.py, issue 13) ---------------------------

@pytest.fixture
def bad(tmp_path: Path) -> Path:
    """Input files of the audit's findings."""
    import athenakin as ak

    toml = ak.Design.default().to_toml()
    (tmp_path / "bom.toml").write_bytes(b"\xef\xbb\xbf" + toml.encode())
    (tmp_path / "nan.toml").write_text(toml.replace("l1 = 0.3", "l1 = nan"))
    (tmp_path / "digits.toml").write_text(toml.replace("l1 = 0.3", "l1 = " + "9" * 5000))
    (tmp_path / "binary.toml").write_bytes(bytes(range(256)))
    T = np.eye(4)
    T[0, 3] = np.nan
    (tmp_path / "nan.json").write_text(json.dumps({"T_b_e": T.tolist()}))
    (tmp_path / "digits.json").write_text('{"T_b_e": [[' + "1" * 5000 + ', 0, 0, 0]]}')
    T[0, 3] = 1e308
    (tmp_path / "far.json").write_text(json.dumps({"T_b_e": T.tolist()}))
    (tmp_path / "path.csv").write_text("x_m,y_m,z_m\n0.25,0,0\n0.253,0.002,0.001\n")
    return tmp_path


@pytest.mark.parametrize("argv,want", [
    # a bad design or RCM file: the message names the file (it used to say only "l1: ...",
    # "TOMLDecodeError: Invalid statement", a bare UnicodeDecodeError, or Python's
    # "Exceeds the limit (4300 digits)")
    (["fk", "-0.1", "0.1", "0.45", "--design", "{d}/nan.toml"], "nan.toml: l1: expected a finite"),
    (["fk", "-0.1", "0.1", "0.45", "--design", "{d}/digits.toml"],
     "digits.toml: design file: a number"),
    (["fk", "-0.1", "0.1", "0.45", "--design", "{d}/binary.toml"],
     "binary.toml: design file is not UTF-8"),
    (["design", "--design", "{d}/nan.toml"], "nan.toml"),
    (["fk", "-0.1", "0.1", "0.45", "--rcm-file", "{d}/nan.json"], "nan.json: T_b_e: expected "
                                                                    "finite values, got nan at "
                                                                    "index (0, 3)"),
    (["fk", "-0.1", "0.1", "0.45", "--rcm-file", "{d}/digits.json"], "digits.json: a number"),
    # an RCM frame far beyond any link: a unit mistake, not "U-joint axes aligned"
    (["fk", "-0.1", "0.1", "0.45", "--rcm-file", "{d}/far.json"], "far.json: T_b_e: the RCM"),
    (["view", "-o", "{d}/v.png", "--rcm", "1e30", "0", "0", "0", "0", "0"], "--rcm: the RCM"),
    # -inf is a (non-finite) value, not a missing positional
    (["fk", "-inf", "0.1", "0.45"], "expected finite values, got -inf"),
    # a denormal rate gave a 2-sample trajectory of infinite duration, exit 0
    (["plan", "{d}/path.csv", "-o", "{d}/t.csv", "--no-plots", "--rate", "5e-324"],
     "rate: expected at least 1"),
])
def test_audit_findings_are_one_line_errors_naming_the_problem(bad, capsys, argv, want):
    before = sorted(p.name for p in bad.iterdir())
    code = main([a.format(d=bad) for a in argv])
    _one_line_error(capsys, code, want=want)
    assert sorted(p.name for p in bad.iterdir()) == before


def test_a_design_file_with_a_byte_order_mark_is_read(bad, capsys):
    assert main(["fk", "-0.1", "0.1", "0.45", "--design", str(bad / "bom.toml")]) == 0
    assert "16 solutions" in capsys.readouterr().out


@pytest.mark.parametrize("argv", [
    ["singularities", "1e308", "0.1", "0.45", "--no-files"],    # not assembled: no value
    ["workspace", "--resolution", "3", "--cone-resolution", "3", "3", "3", "--no-files"],
])
def test_text_output_prints_no_nan(capsys, argv):
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert not re.search(r"\bnan\b", out, re.I), out
    assert not re.search(r"\d{20}", out), out   # no 300-digit fixed-point numbers


@pytest.fixture
def task(tmp_path: Path) -> Path:
    src = Path(__file__).parents[1] / "examples/synthesis/task_pancreas.toml"
    (tmp_path / "task.toml").write_text(src.read_text())
    (tmp_path / "far.toml").write_text(src.read_text().replace(
        "rcm = [0.055234, -0.208281, 0.220767]", "rcm = [1e308, 0, 0]"))
    (tmp_path / "deep.toml").write_text(src.read_text().replace(
        "depth = [0.20, 0.30]", "depth = [0.20, 1e308]"))
    (tmp_path / "many.csv").write_text("x_m,y_m,z_m\n" + "0.25,0,0\n" * 1001)
    (tmp_path / "q.csv").write_text("q1_m,q2_m,q3_m\n-0.1,0.1,0.45\n-0.1,0.1,0.451\n")
    return tmp_path


@pytest.mark.parametrize("argv,want", [
    # synthesize checked nothing up front: 1e20 samples failed with numpy's "Maximum allowed
    # dimension exceeded" after creating the results folder; NaN timeouts were accepted;
    # a huge encoder resolution or task gave NaN metrics in a valid design
    (["synthesize", "{d}/task.toml", "--samples", "99999999999999999999", "-o", "{d}/s"],
     "--samples: expected 1 to 1000000"),
    (["synthesize", "{d}/task.toml", "--connect-timeout", "nan", "-o", "{d}/s"],
     "--connect-timeout"),
    (["synthesize", "{d}/task.toml", "--designs", "-1", "-o", "{d}/s"], "--designs"),
    (["synthesize", "{d}/task.toml", "--top", "-1", "-o", "{d}/s"], "--top"),
    (["synthesize", "{d}/task.toml", "--encoder-resolution", "1e308", "-o", "{d}/s",
      "--no-figures"], "encoder_resolution: expected at most 0.01 m"),
    (["synthesize", "{d}/far.toml", "-o", "{d}/s", "--no-figures"], "rcm: expected coordinates"),
    (["synthesize", "{d}/deep.toml", "-o", "{d}/s", "--no-figures"], "depth: expected 0 <="),
    (["synthesize", "{d}/task.toml", "-o", "{d}/task.toml"], "is a file"),
    # a malformed address: the results folder was created first, and distributed's Client
    # printed a traceback from its __del__ 10 s later
    (["synthesize", "{d}/task.toml", "-o", "{d}/s", "--scheduler", "nan"],
     "scheduler: expected one of"),
    # plan: limits beyond any actuator made Ruckig fail ("error in step 2 in dof: 0");
    # 100,000 waypoints ran for a quarter of an hour
    (["plan", "{d}/many.csv", "-o", "{d}/t.csv", "--no-plots"], "many.csv: 1001 waypoints"),
    (["plan", "{d}/many.csv", "-o", "{d}/t.csv", "--a-max", "1e30"], "--a-max"),
    (["plan", "{d}/many.csv", "-o", "{d}/t.csv", "--v-max", "5e-324"], "--v-max"),
    # options named as typed, not as the library's keywords (jump_m: got -0.001)
    (["track", "{d}/q.csv", "--jump-mm", "-1"], "--jump-mm"),
    (["track", "{d}/q.csv", "--jump-deg", "nan"], "--jump-deg"),
    (["track", "{d}/q.csv", "--jump-mm", "5e-324"], "--jump-mm"),   # was "jump_m: got 0.0"
    (["animate", "-o", "{d}/a.gif", "--cone", "1e308"], "--cone"),
    (["calibrate", "--plan", "99999999999999999999", "-o", "{d}/p.csv"], "--plan"),
    (["calibrate", "--plan", "5", "--candidates", "99999999999999999999", "-o", "{d}/p.csv"],
     "--candidates"),
    (["calibrate", "--plan", "5", "-o", "{d}/p.csv", "--encoder-resolution", "nan"],
     "--encoder-resolution"),
    # the web server waited for ever (deaf to Ctrl-C) on an address it cannot bind
    (["app", "--host", "999.1.1.1", "--port", "0"], "--host"),
    (["app", "--host", "8.8.8.8", "--port", "0"], "--host"),
])
def test_options_are_checked_before_any_work(task, capsys, argv, want):
    if argv[0] == "synthesize":
        pytest.importorskip("dask")
    before = sorted(p.name for p in task.iterdir())
    code = main([a.format(d=task) for a in argv])
    _one_line_error(capsys, code, want=want)
    assert sorted(p.name for p in task.iterdir()) == before


def test_synthesize_needs_force_to_replace_its_figures(task, capsys):
    pytest.importorskip("dask")
    figs = task / "figs"
    figs.mkdir()
    (figs / "pareto.png").write_bytes(b"precious")
    argv = ["synthesize", str(task / "task.toml"), "--samples", "50", "-o", str(task / "s"),
            "--figures", str(figs)]
    _one_line_error(capsys, main(argv), want="--figures")
    assert (figs / "pareto.png").read_bytes() == b"precious" and not (task / "s").exists()
    assert main([*argv, "--force"]) == 0
    assert (figs / "pareto.png").read_bytes().startswith(b"\x89PNG")
    assert not [p for p in figs.iterdir() if p.name.startswith(".")]


def test_track_prints_missing_and_huge_times_readably(task, capsys):
    (task / "s.csv").write_text("t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n,-0.1,0.1,0.451\n"
                                "1e308,nan,nan,nan\n")
    assert main(["track", str(task / "s.csv")]) == 0
    out = capsys.readouterr().out
    assert "t = 1e+308 s" in out and not re.search(r"\d{20}", out), out


def test_app_warning_about_a_bad_rcm_file_names_the_file(bad):
    # `athenakin app --rcm-file nan.json` served the reference set-up with a warning that
    # said "RCM frame: ..." without naming the file
    from athenakin.app._setup_tab import load_setup

    errors: list[str] = []
    load_setup(bad / "nan.json", None, backend="numpy", errors=errors)
    assert len(errors) == 1 and "nan.json" in errors[0], errors


def test_ctrl_c_is_one_line_exit_130_and_leaves_no_file(tmp_path, monkeypatch, capsys):
    # Ctrl-C in a long run printed a KeyboardInterrupt traceback (found by the audit)
    from athenakin.design import Design

    def interrupted(self):
        raise KeyboardInterrupt

    monkeypatch.setattr(Design, "to_toml", interrupted)
    out = tmp_path / "d.toml"
    assert main(["design", "--write", str(out)]) == 130
    err = capsys.readouterr().err
    assert err == "athenakin design: interrupted (no output written)\n"
    assert not list(tmp_path.iterdir())

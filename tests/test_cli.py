"""The command line: fk, ik, demo (text and JSON), errors."""

import importlib
import json
import re
from pathlib import Path

import numpy as np
import pytest

import athenakin as ak
from athenakin.cli import COMMANDS, main


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_every_registered_command_imports():
    for name in COMMANDS:
        assert hasattr(importlib.import_module(f"athenakin.cli._{name}"), "register")


def test_fk_table_and_json(capsys):
    code, out, _ = run(capsys, "fk", "-0.1", "0.1", "0.45")
    assert code == 0 and "16 solutions" in out
    assert out.count(" ok ") == 16
    code, out, _ = run(capsys, "fk", "-0.1", "0.1", "0.45", "--json")
    data = json.loads(out)
    assert data["n_solutions"] == 16
    sol = ak.forward_kinematics([-0.1, 0.1, 0.45], ak.default_rcm_frame())
    np.testing.assert_allclose([s["u_deg"] for s in data["solutions"]], np.degrees(sol.u),
                               atol=1e-9)
    np.testing.assert_allclose([s["tip_m"] for s in data["solutions"]], sol.tip, atol=1e-12)
    np.testing.assert_allclose([s["T_b_tip"] for s in data["solutions"]], sol.T_b_tip,
                               atol=1e-12)


def test_fk_table_shows_the_tool_tip(capsys):
    code, out, _ = run(capsys, "fk", "-0.1", "0.1", "0.45")
    sol = ak.forward_kinematics([-0.1, 0.1, 0.45], ak.default_rcm_frame())
    assert code == 0 and "tip x [m]" in out and "tip z [m]" in out
    row = next(ln for ln in out.splitlines() if ln.split()[:1] == ["0"])
    np.testing.assert_allclose([float(x) for x in row.split()[-3:]], sol.tip[0], atol=1e-5)


def test_ik_three_forms(capsys):
    sol = ak.forward_kinematics([-0.1, 0.1, 0.45], ak.default_rcm_frame())
    u345 = np.degrees(sol.u[0, 2:])
    code, out, _ = run(capsys, "ik", "--u345", *map(str, u345), "--json")
    assert code == 0
    np.testing.assert_allclose(json.loads(out)["q_m"], [-0.1, 0.1, 0.45], atol=1e-9)
    code, out, _ = run(capsys, "ik", "--direction", "0", "90", "--p", "0.2", "--json")
    np.testing.assert_allclose(json.loads(out)["q_m"], [-0.1, 0.1, 0.45], atol=1e-12)
    code, out, _ = run(capsys, "ik", "--tip", "0.25", "0", "0")
    assert code == 0 and "q = (-0.100000, 0.100000, 0.450000) m" in out


def test_design_and_rcm_options(tmp_path, capsys):
    f = tmp_path / "d.toml"
    f.write_text(ak.Design.default().to_toml())
    T = ak.default_rcm_frame()
    g = tmp_path / "rcm.json"
    g.write_text(json.dumps({"T_b_e": T.tolist()}))
    code, out, _ = run(capsys, "fk", "-0.1", "0.1", "0.45", "--design", str(f),
                       "--rcm-file", str(g), "--json")
    assert code == 0 and json.loads(out)["n_solutions"] == 16
    code, out, _ = run(capsys, "fk", "-0.1", "0.1", "0.45", "--rcm", "0", "-0.2", "0.2",
                       "0", "0", "0", "--json")
    assert code == 0
    assert json.loads(out)["T_b_e"][1][3] == -0.2


def test_errors_exit_1_with_named_message(capsys):
    code, _, err = run(capsys, "fk", "0.5", "0.1", "0.45")
    assert code == 1 and "StrokeLimitError" in err and "q = " in err
    code, _, err = run(capsys, "ik", "--direction", "0", "90")
    assert code == 1 and "--direction needs --p" in err
    with pytest.raises(SystemExit) as e:
        main(["fk", "1", "2"])
    assert e.value.code == 2


def test_demo_prints_16_and_ik_recovers(capsys):
    code, out, _ = run(capsys, "demo")
    assert code == 0
    assert "16 solutions" in out and "every solution's IK recovers q" in out
    worst = float(out.strip().split("recovers q to ")[1].split(" m")[0])
    assert worst < 1e-12
    code, out, _ = run(capsys, "demo", "--json")
    data = json.loads(out)
    assert len(data["ik"]) == 16 and all(r["valid"] for r in data["ik"])


def test_readme_fk_and_ik_command_lines_succeed(capsys):
    """The ``fk`` / ``ik`` lines of the README's "Command line" block run as printed."""
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    block = text.split("## Command line", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    lines = [ln.split("#", 1)[0].split() for ln in block.splitlines()]
    commands = [ln[1:] for ln in lines if ln[:1] == ["athenakin"] and ln[1] in ("fk", "ik")]
    assert len(commands) == 5
    for argv in commands:
        code, out, err = run(capsys, *argv)
        assert code == 0, (argv, err)
        assert "q = (" in out or "16 solutions" in out or "16 real solutions" in out, argv


def test_missing_optional_package_names_the_extra(monkeypatch, capsys):
    import athenakin.cli._fk as fk

    def boom(args):
        raise ModuleNotFoundError("No module named 'matplotlib'", name="matplotlib")

    monkeypatch.setattr(fk, "run", boom)
    code, _, err = run(capsys, "fk", "-0.1", "0.1", "0.45")
    assert code == 1 and "pip install 'athenakin[plot]'" in err


def test_import_athenakin_stays_light():
    """Optional heavy dependencies are imported only by the subpackages that need them."""
    import subprocess
    import sys

    code = ("import sys, athenakin, athenakin.cli; athenakin.cli.build_parser(); "
            "heavy = {'sympy', 'matplotlib', 'numba', "
            "'mujoco', 'scipy', 'plotly', 'ruckig', 'toppra', 'pinocchio', 'yourdfpy', "
            "'imageio'}; print(sorted({m.split('.')[0] for m in sys.modules} & heavy))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


@pytest.mark.parametrize("argv", [["fk", "-0.1", "0.1", "0.45"], ["ik", "--tip", "0.25", "0", "0"],
                                  ["ik", "--u345", "-70.143", "90", "0"],
                                  ["ik", "--direction", "0", "90", "--p", "0.2"]])
def test_a_one_shot_command_does_not_load_numba(argv):
    """Issue 30: a one-pose fk loaded numba and every kernel (1.1 s of CPU, and the
    kernel-cache line on stderr) for a millisecond's work. It runs the numpy reference and
    prints what the compiled kernels print (ATHENAKIN_BACKEND set: the library's choice)."""
    import os
    import subprocess
    import sys

    from athenakin._dispatch import numba_available

    code = ("import sys; from athenakin.cli import main; rc = main(sys.argv[1:]); "
            "print('numba loaded:', 'numba' in sys.modules, file=sys.stderr); sys.exit(rc)")
    env = {k: v for k, v in os.environ.items() if k != "ATHENAKIN_BACKEND"}
    fresh = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True,
                           env=env, timeout=600)
    assert fresh.returncode == 0 and fresh.stderr == "numba loaded: False\n", fresh.stderr
    if numba_available():
        compiled = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True,
                                  text=True, env={**env, "ATHENAKIN_BACKEND": "auto"},
                                  timeout=600)
        assert compiled.returncode == 0 and "numba loaded: True" in compiled.stderr
        a, b = compiled.stdout.replace(",", " ").split(), fresh.stdout.replace(",", " ").split()
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):      # the same to the digits shown (a closure
            try:                                 # residual of 1e-16 is rounding noise)
                assert float(x.strip("()")) == pytest.approx(float(y.strip("()")), abs=1e-9)
            except ValueError:
                assert x == y


# --- athenakin design: print / write the design ------------------------------------------
def test_design_prints_and_writes_and_refuses_to_overwrite(tmp_path, capsys):
    code, out, _ = run(capsys, "design")
    assert code == 0 and out.startswith("[design]\n") and "l1 = 0.3" in out
    f = tmp_path / "my_robot.toml"
    code, out, _ = run(capsys, "design", "--write", str(f))
    assert code == 0 and f"wrote {f}" in out
    assert ak.Design.from_toml(f) == ak.Design.default()
    before = f.read_bytes()
    code, _, err = run(capsys, "design", "--write", str(f))
    assert code == 1 and "exists" in err and "--force" in err
    assert f.read_bytes() == before
    example = Path(__file__).resolve().parent.parent / "examples" / "my_robot.toml"
    code, _, _ = run(capsys, "design", "--design", str(example), "--write", str(f), "--force")
    assert code == 0 and ak.Design.from_toml(f) == ak.Design.from_toml(example)
    code, _, err = run(capsys, "design", "--design", str(f), "--write", str(f), "--force")
    assert code != 0 and "input" in err and ak.Design.from_toml(f) == ak.Design.from_toml(example)


def test_readme_demo_with_the_example_design_runs(capsys, monkeypatch):
    """The README's `athenakin demo --design my_robot.toml`, run where the file is."""
    monkeypatch.chdir(Path(__file__).resolve().parent.parent / "examples")
    code, out, _ = run(capsys, "demo", "--design", "my_robot.toml")
    assert code == 0
    _check_demo_numbers(out, ak.Design.from_toml("my_robot.toml"))
    assert "reference design" not in out and "from my_robot.toml" in out   # says whose
    code, out, _ = run(capsys, "demo")
    assert out.startswith("athenakin demo: ATHENA reference design and set-up")
    assert code == 0
    _check_demo_numbers(out, ak.Design.default())


def _table_rows(lines: list[str], header: str) -> list[list[str]]:
    """The cells of the rows of the table whose header line starts with ``header``."""
    i = next(k for k, line in enumerate(lines) if line.startswith(header))
    rows = []
    for line in lines[i + 2:]:                  # after the header and its rule
        if not line.strip():
            break
        rows.append(line.split())
    return rows


def _check_demo_numbers(out: str, design: ak.Design) -> None:
    """Every number the demo prints against the library's own result, each at the
    precision printed relative to its quantity's scale."""
    lines = out.splitlines()
    T = ak.default_rcm_frame(design)
    q_ref = np.array(ak.robot.REFERENCE_Q)
    head = re.search(r"l1\.\.l5 = \[(.*)\] m, tool length (\S+) m", out)
    assert head, out[:400]
    np.testing.assert_allclose([float(v) for v in head.group(1).split(",")], design.lengths,
                               rtol=1e-12)
    assert float(head.group(2)) == pytest.approx(design.tool_length, rel=1e-12)
    i = next(k for k, line in enumerate(lines) if line.startswith("RCM frame T_b_e ="))
    printed_T = np.array([[float(v) for v in line.strip(" []").split()]
                          for line in lines[i + 1:i + 5]])
    # six decimals printed: half a unit of the last digit, relative to the frame's scale
    np.testing.assert_allclose(printed_T, T, rtol=0, atol=1e-6 * np.abs(T).max())
    sol = ak.forward_kinematics(q_ref, T, design)
    n = re.search(r"forward kinematics of q = \[(.*)\] m: (\d+) solutions", out)
    assert n and int(n.group(2)) == int(sol.n_solutions)
    np.testing.assert_allclose([float(v) for v in n.group(1).split(",")], q_ref, rtol=1e-12)
    fk = _table_rows(lines, "slot  mode  p+-")
    assert [int(r[0]) for r in fk] == list(range(16))
    labels = np.array([[int(v) for v in r[1:5]] for r in fk])
    np.testing.assert_array_equal(labels, np.stack([sol.mode, sol.p_sign, sol.ujoint,
                                                    sol.wrist], axis=-1))
    assert [r[5] == "ok" for r in fk] == sol.valid.tolist()
    num = np.array([[float(v) for v in r[6:]] for r in fk])
    p, u_deg, residual, tip = num[:, 0], num[:, 1:6], num[:, 6], num[:, 7:10]
    for got, want in ((p, sol.p), (u_deg, np.degrees(sol.u)), (tip, sol.tip)):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-5 * np.abs(want).max())
    np.testing.assert_allclose(residual, sol.residual, rtol=0.06, atol=1e-300)  # 2 digits
    ik = _table_rows(lines, "slot  mode     q1 [m]")
    assert [int(r[0]) for r in ik] == np.flatnonzero(sol.valid).tolist()
    q_back, pas = ak.inverse_kinematics(T, sol.u[sol.valid, 2:], design, errors="flag")
    assert [int(r[1]) for r in ik] == pas.mode.tolist()
    np.testing.assert_allclose(np.array([[float(v) for v in r[2:5]] for r in ik]), q_back,
                               rtol=0, atol=1e-6 * np.abs(q_ref).max())
    err = np.array([float(r[5]) for r in ik])         # two digits printed
    np.testing.assert_allclose(err, np.abs(q_back - q_ref).max(axis=-1), rtol=0.06,
                               atol=1e-300)
    worst = re.search(r"every solution's IK recovers q to (\S+) m", out)
    assert worst and float(worst.group(1)) == pytest.approx(err.max(), rel=0.06)

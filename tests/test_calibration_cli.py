"""``athenakin calibrate`` and the calibration files (CSV in, plan CSV, TOML, report)."""

import re
import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin import calibration as cal
from athenakin.cli import main

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

D = ak.Design.default()
T = ak.default_rcm_frame(D)
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "calibration"


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_measurement_csv_round_trip(tmp_path):
    data = cal.synthetic_measurements(T, D, n=10, axes=True, rng=1)
    path = tmp_path / "m.csv"
    path.write_text(cal.measurements_csv_text(data.q, data.tips, data.axes))
    back = cal.read_measurements_csv(path)
    assert_allclose(back.q, data.q, rtol=0, atol=0)
    assert_allclose(back.tips, data.tips, rtol=0, atol=0)
    assert_allclose(back.axes, data.axes, rtol=0, atol=0)
    assert back.lines[0] == 5   # three comment lines, then the header


@pytest.mark.parametrize("text, match", [
    ("", "no header row"),
    ("q1_m,q2_m,q3_m,x_m,y_m\n1,2,3,4,5\n", r"missing column\(s\) \['z_m'\]"),
    ("q1_m,q2_m,q3_m,x_m,y_m,z_m\n", "no data rows"),
    ("q1_m,q2_m,q3_m,x_m,y_m,z_m\n-0.1,0.1,0.45,0,0\n", "line 2: expected 6 fields"),
    ("# c\nq1_m,q2_m,q3_m,x_m,y_m,z_m\n-0.1,0.1,abc,0,0,0\n", "line 3, column 'q3_m'"),
    ("q1_m,q2_m,q3_m,x_m,y_m,z_m,dx\n-0.1,0.1,0.4,0,0,0,1\n", "axis columns must be all"),
])
def test_malformed_csv_is_a_named_error(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(cal.MeasurementFileError, match=match):
        cal.read_measurements_csv(path)


def test_mode_column_is_read_per_row(tmp_path, capsys):
    data = cal.synthetic_measurements(T, D, n=12, mode=-1, rng=6,
                                      options=cal.SyntheticOptions(noise=0.0))
    text = cal.measurements_csv_text(data.q, data.tips).splitlines()
    head = next(i for i, ln in enumerate(text) if ln.startswith("q1_m"))
    text[head] += ",mode"
    text[head + 1:] = [ln + ",-1" for ln in text[head + 1:]]
    path = tmp_path / "m.csv"
    path.write_text("\n".join(text) + "\n")
    assert cal.read_measurements_csv(path).mode.tolist() == [-1] * 12
    code, out, err = run(capsys, "calibrate", path, "-o", tmp_path / "c.toml", "--no-report")
    assert code == 0, err
    assert abs(ak.Design.from_toml(tmp_path / "c.toml").l1 - data.true_design.l1) < 1e-9
    path.write_text("\n".join(text).replace(",-1", ",2") + "\n")
    with pytest.raises(cal.MeasurementFileError, match="column 'mode'"):
        cal.read_measurements_csv(path)


def test_tips_in_millimetres_are_caught(tmp_path):
    data = cal.synthetic_measurements(T, D, n=30, rng=7, options=cal.SyntheticOptions(noise=0.0))
    with pytest.warns(cal.CalibrationWarning, match="check the units"), \
            pytest.raises(cal.CalibrationError):
        cal.calibrate(data.q, data.tips * 1000, T, D)


def test_empty_and_nan_cells_become_bad_rows(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("q1_m,q2_m,q3_m,x_m,y_m,z_m,extra\n-0.1,0.1,0.45,,0,0,a\n"
                    "-0.1,0.1,0.45,nan,0,0,b\n")
    m = cal.read_measurements_csv(path)
    assert np.isnan(m.tips[:, 0]).all() and m.axes is None


def test_cli_calibrates_the_example_data_set(tmp_path, capsys):
    out = tmp_path / "cal.toml"
    code, text, err = run(capsys, "calibrate", EXAMPLE / "measurements.csv", "-o", out,
                          "--params", "default", "offsets", "--loss", "soft_l1")
    assert code == 0, err
    assert "1 of 80 rows excluded" in text and "2 row(s) flagged as outliers" in text
    assert "q3_offset" in text and "RMS tip residual" in text
    cal_design = ak.Design.from_toml(out)
    truth = tomllib.loads((EXAMPLE / "truth.toml").read_text())["truth"]
    table = tomllib.loads(out.read_text())["calibration"]
    for name in ("l1", "l2", "l3", "l4", "l5", "tool_length"):
        assert abs(getattr(cal_design, name) - truth[name]) < 4 * table["std"][name]
    for i in range(3):
        assert abs(table["q_offset"][i] - truth[f"q{i + 1}_offset"]) < \
            4 * table["std"][f"q{i + 1}_offset"]
    assert table["rows_outliers"] == 2 and table["rows_excluded"] == 1
    report = tmp_path / "cal_report.md"
    assert "| l1 |" in report.read_text()
    for fig in ("residuals", "parameters", "tip_error"):
        assert (tmp_path / f"cal_report_{fig}.png").stat().st_size > 1000


def test_cli_report_is_checked_first_and_written_with_the_toml(tmp_path, capsys):
    """An existing report figure stops the command before any work; nothing is written."""
    out = tmp_path / "cal.toml"
    fig = tmp_path / "cal_report_residuals.png"
    fig.write_bytes(b"keep")
    code, _, err = run(capsys, "calibrate", EXAMPLE / "measurements.csv", "-o", out)
    assert code == 1 and "--force" in err and "cal_report_residuals.png" in err
    assert not out.exists() and not (tmp_path / "cal_report.md").exists()
    assert fig.read_bytes() == b"keep"
    code, text, err = run(capsys, "calibrate", EXAMPLE / "measurements.csv", "-o", out,
                          "--force")
    assert code == 0, err
    assert out.exists() and fig.read_bytes() != b"keep" and "cal_report.md" in text


def test_html_report(tmp_path):
    data = cal.synthetic_measurements(T, D, n=20, rng=5)
    res = cal.calibrate(data.q, data.tips, T, D)
    files = cal.write_report(res, tmp_path / "r.html", figures=False)
    text = files[0].read_text()
    assert text.startswith("<!DOCTYPE html>") and text.count("<tr>") == 7
    assert "<td>tool_length</td>" in text and "<b>" in text


def test_cli_tracker_frame_without_report(tmp_path, capsys):
    data = cal.synthetic_measurements(T, D, n=30, frame="tracker", rng=3)
    src = tmp_path / "m.csv"
    src.write_text(cal.measurements_csv_text(data.q, data.tips, frame="tracker"))
    out = tmp_path / "c.toml"
    code, text, err = run(capsys, "calibrate", src, "-o", out, "--frame", "tracker",
                          "--no-report")
    assert code == 0, err
    table = tomllib.loads(out.read_text())["calibration"]
    assert table["frame"] == "tracker" and "reg_tx" in table["estimated"]
    assert_allclose(np.array(table["T_t_b"]), data.T_t_b, rtol=0, atol=1e-4)
    assert not (tmp_path / "c_report.md").exists()


def test_cli_plan_writes_poses_that_read_back(tmp_path, capsys):
    out = tmp_path / "poses.csv"
    code, text, err = run(capsys, "calibrate", "--plan", "15", "-o", out, "--candidates",
                          "400", "--params", "default", "q3_offset")
    assert code == 0, err
    assert "wrote 15 poses" in text
    plan = cal.read_measurements_csv(out, require_tips=False)
    assert plan.q.shape == (15, 3) and plan.tips is None
    assert np.all(cal.check_measurements(plan.q, T, D).usable)


@pytest.mark.parametrize("args, match", [
    (["--plan", "2"], "3 n > 6"),
    (["--params", "l9"], "unknown parameter 'l9'"),
    ([], "expected a measurement file"),
])
def test_cli_errors(tmp_path, capsys, args, match):
    src = [EXAMPLE / "measurements.csv"] if "--params" in args else []
    code, _, err = run(capsys, "calibrate", *src, "-o", tmp_path / "x.toml", *args)
    assert code == 1 and match in err


def test_cli_unidentifiable_data_is_refused(tmp_path, capsys):
    q = cal.random_poses(30, T, D, rng=4)
    data = cal.synthetic_measurements(T, D, q=q, frame="tracker", rng=4,
                                      options=cal.SyntheticOptions(noise=0.0))
    src = tmp_path / "m.csv"
    src.write_text(cal.measurements_csv_text(data.q, data.tips))
    code, _, err = run(capsys, "calibrate", src, "-o", tmp_path / "c.toml", "--frame",
                       "tracker", "--params", "default", "offsets", "rcm")
    assert code == 1 and "NotIdentifiableError" in err and "rail axis" in err
    assert not (tmp_path / "c.toml").exists()


def test_docs_python_blocks_run():
    text = (Path(__file__).resolve().parents[1] / "docs" / "calibration.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks
    for code in blocks:
        exec(compile(code, "docs/calibration.md", "exec"), {})


def test_calibrate_docstring_example():
    import doctest

    import athenakin.calibration._solve as mod

    assert doctest.testmod(mod).failed == 0

"""Design: defaults, validation, TOML round trip."""

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

import athenakin as ak

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def test_lengths_only_design_is_unlimited_with_defaults():
    d = ak.Design(l1=0.30, l2=0.10, l3=0.25, l4=0.15, l5=0.40)
    assert d.q_min is None and d.q_max is None
    # q3 is a length: its lower limit is 0 even without strokes (issue 13)
    assert d.stroke_min.tolist() == [-np.inf, -np.inf, 0.0] and np.all(d.stroke_max == np.inf)
    assert d.ab_order == "q1<q2" and d.h_sign == -1.0
    assert d.tool_length == 0.45


def test_default_design_documented_values():
    d = ak.Design.default()
    np.testing.assert_array_equal(d.lengths, [0.30, 0.10, 0.25, 0.15, 0.40])
    assert d.q_min == (-0.30, -0.10, 0.20) and d.q_max == (0.10, 0.30, 0.70)


def test_design_is_frozen_and_keyword_only():
    d = ak.Design.default()
    with pytest.raises(dataclasses.FrozenInstanceError):
        d.l1 = 1.0  # type: ignore[misc]
    with pytest.raises(TypeError):
        ak.Design(0.3, 0.1, 0.25, 0.15, 0.4)  # type: ignore[misc]


@pytest.mark.parametrize("kw, exc, match", [
    ({"l1": -0.3}, ak.InvalidInputError, "l1: expected a positive number, got -0.3"),
    ({"l2": float("nan")}, ak.InvalidInputError, "l2: expected a finite number"),
    ({"l3": "0.25"}, TypeError, "l3: expected a real number, got str"),
    ({"q_min": (0, 0)}, ak.InvalidInputError, "q_min: expected 3 numbers"),
    ({"q_min": (0.5, 0, 0), "q_max": (0.1, 1, 1)}, ak.InvalidInputError, "q_min <= q_max"),
    ({"ab_order": "left"}, ak.InvalidInputError, "ab_order: expected one of"),
    ({"tool_length": 0.0}, ak.InvalidInputError, "tool_length: expected a positive"),
])
def test_design_validation(kw, exc, match):
    base = dict(l1=0.30, l2=0.10, l3=0.25, l4=0.15, l5=0.40)
    base.update(kw)
    with pytest.raises(exc, match=match):
        ak.Design(**base)


def test_toml_round_trip(tmp_path):
    for d in (ak.Design.default(),
              ak.Design(l1=0.3, l2=0.1, l3=0.25, l4=0.15, l5=0.4, q_min=(-np.inf, -1, 0),
                        q_max=(1, np.inf, 2), ab_order="q1>q2", tool_length=0.3)):
        f = tmp_path / "d.toml"
        f.write_text(d.to_toml())
        assert ak.Design.from_toml(f) == d


def test_toml_errors(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text("[design]\nl1 = 0.3\nl2 = 0.1\nl3 = 0.25\nl4 = 0.15\nl5 = 0.4\nlength = 3\n")
    with pytest.raises(ak.InvalidInputError, match="unknown key\\(s\\) \\['length'\\]"):
        ak.Design.from_toml(f)
    f.write_text("l1 = 0.3\n")
    with pytest.raises(ak.InvalidInputError, match="missing required length"):
        ak.Design.from_toml(f)


@pytest.mark.parametrize("line, match", [
    ("q_max = 0.45", "q_max: expected a list of 3 numbers"),  # found by the fuzzer (CI)
    ('q_min = "abc"', "q_min: expected a list of 3 numbers"),
    ("q_min = {a = 1}", "q_min: expected a list of 3 numbers"),
    ('q_max = ["a", 0.3, 0.7]', "q_max\\[0\\]: expected a real number, got str"),
    ('l1 = "0.3"', "l1: expected a real number, got str"),
    ("tool_length = true", "tool_length: expected a real number, got bool"),
    ("name = 5", "name: expected str, got int"),
    ("ab_order = [1]", "ab_order: expected one of"),
])
def test_toml_wrong_types_are_invalid_input(tmp_path, line, match):
    """A value of the wrong type in a design file is bad input (InvalidInputError), never a
    bare TypeError: the file readers raise only named errors (issue 13)."""
    f = tmp_path / "bad.toml"
    base = "l1 = 0.3\nl2 = 0.1\nl3 = 0.25\nl4 = 0.15\nl5 = 0.4\n"
    key = line.split(" =")[0]
    base = "\n".join(x for x in base.splitlines() if not x.startswith(key + " "))
    f.write_text("[design]\n" + base + "\n" + line + "\n")
    with pytest.raises(ak.InvalidInputError, match=match):
        ak.Design.from_toml(f)


def test_ab_order_reversed_mirrors_actuators():
    """With q1 > q2 the same pose is reached by swapping q1 and q2."""
    d1 = ak.Design.default()
    d2 = dataclasses.replace(d1, ab_order="q1>q2", q_min=None, q_max=None)
    T = ak.default_rcm_frame(d1)
    q = ak.robot.REFERENCE_Q
    s1 = ak.forward_kinematics(q, T, d1)
    s2 = ak.forward_kinematics(q[[1, 0, 2]], T, d2)
    np.testing.assert_allclose(s1.T_b_s, s2.T_b_s, atol=0)
    q2, _ = ak.inverse_kinematics(T, s1.u[0, 2:], d2)
    np.testing.assert_allclose(q2, q[[1, 0, 2]], atol=1e-12)


# --- TOML written by a library (tomli-w): any name, unlimited strokes ------------------
@pytest.mark.parametrize("name", ['quote "inside"', "back\\slash", "two\nlines", "tab\there",
                                  "ünïcödé 設計", "'single'", "trailing \\", ""])
def test_toml_round_trip_of_any_name(tmp_path, name):
    d = ak.Design(l1=0.3, l2=0.1, l3=0.25, l4=0.15, l5=0.4, q_min=(-np.inf, -0.1, 0.2),
                  q_max=(0.1, np.inf, np.inf), name=name)
    text = d.to_toml()
    assert tomllib.loads(text)["design"]["name"] == name      # valid TOML
    f = tmp_path / "d.toml"
    f.write_text(text, encoding="utf-8")
    assert ak.Design.from_toml(f) == d


def test_write_toml_refuses_to_overwrite(tmp_path):
    f = tmp_path / "d.toml"
    d = ak.Design.default()
    assert d.write_toml(f) == f and ak.Design.from_toml(f) == d
    with pytest.raises(FileExistsError):
        d.write_toml(f)
    other = ak.Design(l1=0.31, l2=0.1, l3=0.25, l4=0.15, l5=0.4)
    other.write_toml(f, overwrite=True)
    assert ak.Design.from_toml(f) == other


def test_example_design_file_loads():
    d = ak.Design.from_toml(EXAMPLES / "my_robot.toml")
    assert d.tool_length == 0.50 and d.name.startswith("my robot")
    assert ak.Design.from_mapping(tomllib.loads(d.to_toml())["design"]) == d


def test_toml_not_utf8_or_too_deep_is_invalid_input(tmp_path):
    """One TOML reader (athenakin._toml) for designs, tasks and bounds: named errors."""
    from athenakin.synthesis import Task, TaskFileError

    f = tmp_path / "bad.toml"
    f.write_bytes(b"[design]\nname = \"\xff\"\n")
    with pytest.raises(ak.InvalidInputError, match="not UTF-8 text"):
        ak.Design.from_toml(f)
    f.write_bytes(b"a = " + b"[" * 100_000 + b"]" * 100_000 + b"\n")
    with pytest.raises(ak.InvalidInputError, match="nested too deeply"):
        ak.Design.from_toml(f)
    with pytest.raises(TaskFileError, match="nested too deeply"):
        Task.from_toml(f)


def test_a_design_typed_in_millimetres_warns_naming_the_unit():
    import warnings

    from athenakin.design import LIKELY_MM_ABOVE, UnitWarning

    with pytest.warns(UnitWarning, match=r"l1 = 300; .*millimetres \(divide by 1000\)"):
        ak.Design(l1=300, l2=100, l3=250, l4=150, l5=400, tool_length=450, name="mm")
    with pytest.warns(UnitWarning, match=r"q_max = \[100.0, 300.0, 700.0\]"):
        ak.Design(l1=0.3, l2=0.1, l3=0.25, l4=0.15, l5=0.4, q_max=(100, 300, 700))
    with warnings.catch_warnings():
        warnings.simplefilter("error")                # metres, and unlimited strokes: silent
        ak.Design.default()
        ak.Design(l1=0.3, l2=0.1, l3=0.25, l4=0.15, l5=LIKELY_MM_ABOVE,
                  q_min=(-np.inf, -1.0, 0.0), q_max=None)

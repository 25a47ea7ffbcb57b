"""The tolerance policy of athenakin.testing: relative to the quantity's scale, texts parsed.

Constructions with known answers: a correct pair that differs in its last bits at any
magnitude passes, a change of formula fails; NaN and infinity patterns and shapes count;
URDF-like documents agree through a last-digit change of a printed float and differ through
a changed name, tag, child count or a number beyond 1e-14 of its attribute's scale.
"""

from __future__ import annotations

import numpy as np
import pytest

from athenakin.errors import InvalidInputError
from athenakin.testing import (
    IMPLEMENTATION_RTOL,
    TEXT_RTOL,
    assert_allclose_scaled,
    assert_xml_equal,
    scaled_differences,
    xml_differences,
)

EPS = np.finfo(float).eps


@pytest.mark.parametrize("magnitude", [1e-9, 1e-3, 1.0, 1180.8, 4.3e19])
def test_last_bit_differences_pass_at_any_magnitude(magnitude):
    rng = np.random.default_rng(1)
    a = magnitude * rng.uniform(-1.0, 1.0, (50, 3))
    b = a * (1.0 + 8 * EPS * rng.choice([-1.0, 1.0], a.shape))
    assert_allclose_scaled(a, b)
    # the case of the other CPU: 1180.8017955425034 against 1180.801795542511
    assert_allclose_scaled(np.array([1180.8017955425034]), np.array([1180.801795542511]))


@pytest.mark.parametrize("magnitude", [1e-9, 1.0, 1180.8])
def test_a_change_beyond_the_tolerance_fails(magnitude):
    a = magnitude * np.array([0.3, -0.7, 1.0])
    b = a.copy()
    b[1] += 10 * IMPLEMENTATION_RTOL * magnitude
    with pytest.raises(AssertionError, match=r"worst at \(1,\)"):
        assert_allclose_scaled(a, b, err_msg="x")


def test_entries_near_zero_are_held_to_the_quantity_scale():
    # a round-off of a zero beside entries of order 1 is no difference; the same
    # difference in a quantity whose scale is 1e-20 is
    assert_allclose_scaled(np.array([1.0, 1e-17]), np.array([1.0, 0.0]))
    with pytest.raises(AssertionError):
        assert_allclose_scaled(np.array([1e-20, 1e-17]), np.array([1e-20, 0.0]))
    # an explicit per-column scale
    a = np.array([[1000.0, 1e-3], [2000.0, 2e-3]])
    b = a + np.array([[1e-10, 0.0], [0.0, 1e-13]])
    assert_allclose_scaled(a, b)                           # one scale: 2000
    with pytest.raises(AssertionError):
        assert_allclose_scaled(a, b, scale=np.abs(a).max(axis=0))


def test_patterns_shapes_and_integers():
    assert "NaN pattern" in scaled_differences([1.0, np.nan], [1.0, 2.0])
    assert scaled_differences([1.0, np.nan], [1.0, np.nan]) == ""
    assert "infinities" in scaled_differences([np.inf], [-np.inf])
    assert scaled_differences([np.inf, 1.0], [np.inf, 1.0]) == ""
    assert "shape" in scaled_differences(np.zeros(3), np.zeros((3, 1)))
    assert "integer" in scaled_differences(np.array([1, 2]), np.array([1, 3]))
    assert scaled_differences(np.zeros(0), np.zeros(0)) == ""
    with pytest.raises(InvalidInputError, match="scale"):
        scaled_differences([1.0], [1.0], scale=-1.0)
    with pytest.raises(InvalidInputError, match="rtol"):
        scaled_differences([1.0], [1.0], rtol=float("nan"))


URDF = ('<robot name="athena"><link name="l1"><inertial><origin xyz="{x} 0 0.3" '
        'rpy="0 0 0"/><mass value="1.25"/></inertial></link>'
        '<joint name="q1" type="prismatic"><parent link="base"/></joint></robot>')


def test_xml_last_digits_are_no_difference():
    assert_xml_equal(URDF.format(x="0.41231056256176607"), URDF.format(x="0.4123105625617661"))
    # the zero of an attribute held to the attribute's scale (0.3 here)
    assert not xml_differences(URDF.format(x="1e-17"), URDF.format(x="0"))


def test_xml_real_differences_are_named():
    base = URDF.format(x="0.4")
    assert xml_differences(URDF.format(x=repr(0.4 + 100 * TEXT_RTOL)), base)
    bad = xml_differences(base.replace('name="q1"', 'name="q2"'), base)
    assert bad and "q1" in bad[0] and "q2" in bad[0]
    assert xml_differences(base.replace("prismatic", "revolute"), base)
    assert xml_differences(base.replace("<mass", "<massx"), base)
    assert xml_differences(base.replace('<parent link="base"/>', ""), base)
    with pytest.raises(AssertionError, match="XML documents differ"):
        assert_xml_equal(base.replace('"1.25"', '"1.5"'), base)
    with pytest.raises(TypeError, match="actual"):
        xml_differences(b"<a/>", "<a/>")

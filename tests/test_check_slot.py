"""One check_slot (issue 28): every public function checks an FK slot the same way."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import athenakin as ak
from athenakin._validation import check_slot
from athenakin.errors import InvalidInputError

SRC = Path(ak.__file__).parent


@pytest.mark.parametrize("slot, want", [(0, 0), (15, 15), (np.int64(7), 7), (np.uint8(3), 3)])
def test_slots_are_ints(slot, want):
    assert check_slot(slot) == want and type(check_slot(slot)) is int


@pytest.mark.parametrize("slot", [16, -1, True, 1.0, "0", None, "all", np.array([1])])
def test_bad_slots_are_named(slot):
    with pytest.raises(InvalidInputError, match=r"^slot: expected an integer in 0\.\.15, got"):
        check_slot(slot)


def test_all_where_offered():
    assert check_slot("all", allow_all=True) == "all"
    with pytest.raises(InvalidInputError, match="0..15 or 'all'"):
        check_slot("ALL", allow_all=True)
    with pytest.raises(InvalidInputError, match="^zero_slot: "):
        check_slot(99, "zero_slot")


@pytest.mark.parametrize("call", [
    lambda: ak.collision.clearance([-0.1, 0.1, 0.45], ak.default_rcm_frame(), slot=16),
    lambda: ak.dynamics.statics([-0.1, 0.1, 0.45], slot=True),
    lambda: ak.sim.mechanism_joint_values(slot=-1),
    lambda: ak.plot.robot_geometry(slot=2.0),
])
def test_public_functions_use_it(call):
    with pytest.raises(InvalidInputError, match=r"slot: expected an integer in 0\.\.15"):
        call()


def test_no_module_checks_a_slot_range_by_hand():
    pattern = re.compile(r"0 <= slot < 16")
    offenders = [str(p.relative_to(SRC)) for p in SRC.rglob("*.py")
                 if pattern.search(p.read_text(encoding="utf-8"))]
    assert not offenders, offenders

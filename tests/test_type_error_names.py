"""A TypeError names the parameter that was given the wrong type, as its first word."""

from __future__ import annotations

import re

import pytest

import athenakin as ak


def _cases():
    from athenakin.calibration import CalibrationOptions
    from athenakin.collision import Bodies, Environment
    from athenakin.motion import PlanOptions
    from athenakin.synthesis import CollisionSpec, StudyOptions

    return [
        ("data", lambda: ak.Design.from_mapping(3)),
        ("data", lambda: Environment.from_mapping([1, 2])),
        ("data", lambda: Bodies.from_mapping("bodies")),
        ("data", lambda: CollisionSpec.from_mapping(3)),
        ("data", lambda: PlanOptions.from_mapping(3)),
        ("data", lambda: StudyOptions.from_mapping([("progress", True)])),
        ("data", lambda: CalibrationOptions.from_mapping(None)),
        ("radii", lambda: Bodies.default().with_radius({1: 0.01})),
        ("cond_max", lambda: ak.dynamics.force_metrics([[-0.1, 0.1, 0.45]],
                                                        ak.default_rcm_frame(),
                                                        ak.Design.default(), slot=0,
                                                        cond_max="100")),
    ]


@pytest.mark.parametrize("index", range(9))
def test_the_message_starts_with_the_parameter(index):
    name, call = _cases()[index]
    with pytest.raises(TypeError) as info:
        call()
    assert re.match(rf"{re.escape(name)}\b", str(info.value)), str(info.value)


def test_an_unknown_body_of_with_radius_names_its_keyword():
    from athenakin.collision import Bodies

    with pytest.raises(ValueError, match=r"^by_name: unknown body 'elbow'"):
        Bodies.default().with_radius(elbow=0.01)
    with pytest.raises(ValueError, match=r"^radii: unknown body 'elbow'"):
        Bodies.default().with_radius({"elbow": 0.01})


def test_check_fk_with_mujoco_names_home_q():
    pytest.importorskip("mujoco")
    from athenakin.sim import check_fk_with_mujoco

    with pytest.raises((TypeError, ValueError), match=r"^home_q\b"):
        check_fk_with_mujoco([[-0.1, 0.1, 0.45]], home_q="abc")

"""docs/foxglove_teleop_layout.json and the recorded master of tools/foxglove-shot (teleop).

The screenshot itself (docs/figures/foxglove_teleop.png) needs Chromium and Foxglove Studio
(``python docs/figures/regenerate.py foxglove``); these tests check what it is made from.
"""

import importlib.util
import json
import re
from pathlib import Path

import pytest

from athenakin.teleop import CRTK_TOPICS, TELEOP_STATUS_MSGDEF

ROOT = Path(__file__).resolve().parents[1]
LAYOUT = ROOT / "docs" / "foxglove_teleop_layout.json"
#: The fields of each session topic's message type that a layout may plot.
FIELDS = {
    "sensor_msgs/msg/JointState": r"(position|velocity|effort)\[[0-2]\]",
    "geometry_msgs/msg/PoseStamped": r"pose\.position\.[xyz]",
    "geometry_msgs/msg/PointStamped": r"point\.[xyz]",
}
TOPIC_TYPES = {
    CRTK_TOPICS["measured_js"]: "sensor_msgs/msg/JointState",
    CRTK_TOPICS["setpoint_js"]: "sensor_msgs/msg/JointState",
    CRTK_TOPICS["measured_cp"]: "geometry_msgs/msg/PoseStamped",
    CRTK_TOPICS["servo_cp"]: "geometry_msgs/msg/PoseStamped",
    CRTK_TOPICS["master"]: "geometry_msgs/msg/PointStamped",
}


def _leaves(node):
    if isinstance(node, str):
        return [node]
    assert set(node) >= {"first", "second", "direction"}, node
    assert node["direction"] in ("row", "column")
    return _leaves(node["first"]) + _leaves(node["second"])


def test_teleop_layout_names_session_topics_and_fields():
    """Every path of the layout is a topic and field that write_session_mcap writes."""
    layout = json.loads(LAYOUT.read_text())
    status_fields = set(re.findall(r"^\w+(?:/\w+)*\s+(\w+)", TELEOP_STATUS_MSGDEF, flags=re.M))
    paths = [p["value"] for c in layout["configById"].values() for p in c.get("paths", [])]
    assert len(paths) >= 10
    seen = set()
    for value in paths:
        topic, field = value.split(".", 1)
        seen.add(topic)
        if topic == CRTK_TOPICS["status"]:
            assert field in status_fields, value
        else:
            assert re.fullmatch(FIELDS[TOPIC_TYPES[topic]], field), value
    assert seen == {CRTK_TOPICS[k] for k in ("measured_js", "setpoint_js", "measured_cp",
                                             "servo_cp", "status", "master")}


def test_teleop_layout_is_what_foxglove_1_48_reads():
    """Panels and values that Foxglove Studio 1.48 accepts (as docs/foxglove_layout.json)."""
    layout = json.loads(LAYOUT.read_text())
    panel_ids = _leaves(layout["layout"])
    assert sorted(panel_ids) == sorted(layout["configById"])
    assert {i.split("!")[0] for i in panel_ids} == {"Plot", "StateTransitions"}
    for panel_id, config in layout["configById"].items():
        assert config["isSynced"] is True
        for path in config["paths"]:
            assert path["timestampMethod"] == "headerStamp", panel_id
        if panel_id.startswith("Plot!"):
            assert config["title"]                      # shot.py waits for the first title
            assert config["legendDisplay"] in ("floating", "top", "left"), panel_id
            assert config["xAxisVal"] == "timestamp"


def test_shot_master_recording_replays(tmp_path):
    """tools/foxglove-shot/shot.py's recorded master reads back with its clutch and gap."""
    pytest.importorskip("mcap_ros2")
    pytest.importorskip("rosbags")
    from athenakin.teleop import read_master

    spec = importlib.util.spec_from_file_location("foxglove_shot",
                                                  ROOT / "tools/foxglove-shot/shot.py")
    shot = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(shot)
    assert set(shot.RECORDINGS) == {"track", "teleop"}
    assert (ROOT / shot.RECORDINGS["teleop"][0]) == LAYOUT
    rec = tmp_path / "master.mcap"
    shot.write_master(rec)
    samples = list(read_master(rec))
    assert len(samples) == 8000 and abs(samples[-1][0] - 7.999) < 1e-9
    t = {round(s[0] * 1000): s for s in samples}
    assert t[3500][2] is False and t[2500][2] is True and t[4500][2] is True   # the pedal
    assert t[5550][1] is None and t[5450][1] is not None                       # the gap
    assert t[6700][1][0] - t[6400][1][0] > 0.25                                # the jump

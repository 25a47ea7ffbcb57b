"""The tracker's clearance reaches /athena/status of the MCAP output (issues 20 and 22)."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin.robot import REFERENCE_Q

ros = pytest.importorskip("athenakin.ros")
pytest.importorskip("mcap_ros2")
collision = pytest.importorskip("athenakin.collision")


def _status(path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(path, "rb") as f:
        r = make_reader(f, decoder_factories=[DecoderFactory()])
        return [m for _, _, _, m in r.iter_decoded_messages(topics=["/athena/status"])]


def test_status_carries_the_clearance_of_the_tracker(tmp_path):
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    n = 40
    q = REFERENCE_Q + np.linspace(0, 0.01, n)[:, None] * np.array([1.0, -1.0, 0.5])
    q[7] = np.nan                                          # a lost reading keeps NaN
    stamps = np.arange(n, dtype=np.int64) * 1_000_000
    bodies = collision.Bodies.default(d)
    margin = 1.0                                           # every valid sample is "near"
    ros.track_to_mcap(stamps, q, tmp_path / "o.mcap", T, d, bodies=bodies,
                      clearance_margin=margin)
    st = _status(tmp_path / "o.mcap")
    assert len(st) == n
    log = ak.motion.track(q, T, d, bodies=bodies, clearance_margin=margin)
    got = np.array([m.clearance_m for m in st])
    assert_allclose(got, log.clearance, rtol=0, atol=1e-12, equal_nan=True)
    assert np.isnan(got[7]) and np.isfinite(np.delete(got, 7)).all()
    near = int(ak.motion.TrackFlag.NEAR_COLLISION)
    flags = np.array([m.clearance_flags for m in st])
    assert (flags[np.isfinite(got)] & near).all()


def test_status_without_bodies_has_no_clearance(tmp_path):
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    q = np.tile(REFERENCE_Q, (5, 1))
    ros.track_to_mcap(np.arange(5, dtype=np.int64), q, tmp_path / "o.mcap", T, d)
    st = _status(tmp_path / "o.mcap")
    assert all(np.isnan(m.clearance_m) and m.clearance_flags == 0 for m in st)


@pytest.mark.parametrize("args, option", [(["--scale", "nan"], "--scale"),
                                          (["--scale", "-1"], "--scale"),
                                          (["--topic", "nan"], "--topic"),
                                          (["--topic", "/a b"], "--topic")])
def test_track_refuses_a_bad_topic_or_scale_for_any_input(tmp_path, capsys, args, option):
    from athenakin.cli import main

    csv = tmp_path / "stream.csv"
    csv.write_text("q1_m,q2_m,q3_m\n" + "".join(f"{q[0]},{q[1]},{q[2]}\n"
                                                for q in np.tile(REFERENCE_Q, (3, 1))))
    assert main(["track", str(csv), *args]) != 0
    err = capsys.readouterr().err
    assert option in err and len(err.strip().splitlines()) == 1

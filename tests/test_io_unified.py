"""One JSON converter and one CSV reader for the whole package (issue 12.10)."""

import json
import math

import numpy as np
import pytest

from athenakin import _serialize
from athenakin.cli import _animate, _common
from athenakin.motion import PathFileError, read_q_stream_csv
from athenakin.motion import _io as motion_io


def test_one_json_converter():
    assert _common.to_jsonable is _serialize.to_jsonable
    assert not hasattr(motion_io, "_jsonable")
    obj = {"a": np.array([1.0, np.nan, np.inf]), "n": np.int64(3), "b": np.bool_(True),
           "t": (np.float32(0.5), [np.float64(-np.inf)])}
    text = _serialize.json_text(obj)
    assert json.loads(text) == {"a": [1.0, None, None], "n": 3, "b": True, "t": [0.5, [None]]}
    assert _common.dump_json(obj) == _serialize.json_text(obj, indent=2)
    assert "NaN" not in text and "Infinity" not in text


def test_one_csv_reader_for_q_files(tmp_path, monkeypatch):
    """animate's --q-file goes through the motion subpackage's reader (same errors)."""
    calls = []
    real = motion_io._read_table

    def spy(*args, **kwargs):
        calls.append(args)
        return real(*args, **kwargs)

    monkeypatch.setattr(motion_io, "_read_table", spy)
    f = tmp_path / "q.csv"
    f.write_text("t_s,q1_m,q2_m,q3_m\n0,-0.1,0.1,0.45\n0.1,-0.1,0.1,0.46\n")
    q, t = _animate.read_q_file(f)
    np.testing.assert_array_equal(q, [[-0.1, 0.1, 0.45], [-0.1, 0.1, 0.46]])
    np.testing.assert_array_equal(t, [0.0, 0.1])
    assert calls


@pytest.mark.parametrize("text", ["-0.1 0.1 0.45\n-0.1 0.1 0.46\n",
                                  "# q1 q2 q3\n-0.1, 0.1, 0.45\n\n-0.1,0.1,0.46\n"])
def test_headerless_q_stream(tmp_path, text):
    f = tmp_path / "q.txt"
    f.write_text(text)
    q, t = read_q_stream_csv(f)
    assert t is None
    np.testing.assert_array_equal(q, [[-0.1, 0.1, 0.45], [-0.1, 0.1, 0.46]])


def test_headerless_q_stream_errors(tmp_path):
    f = tmp_path / "q.txt"
    f.write_text("0 0 0\n1 2\n")
    with pytest.raises(PathFileError, match=r"line 2: expected 3 values per row"):
        read_q_stream_csv(f)
    f.write_text("0 0 0\n1 2 x\n")
    with pytest.raises(PathFileError, match="line 2, column 'q3_m': expected a number"):
        read_q_stream_csv(f)


def test_animate_refuses_incomplete_readings(tmp_path):
    f = tmp_path / "q.csv"
    f.write_text("q1_m,q2_m,q3_m\n-0.1,0.1,0.45\n-0.1,,0.45\n")
    with pytest.raises(ValueError, match="reading 1 is incomplete"):
        _animate.read_q_file(f)
    assert math.isnan(read_q_stream_csv(f)[0][1, 1])    # the tracker's reader keeps it (LOST)


@pytest.mark.parametrize("bad", [0, 1, True, None, b"q.csv"])
def test_path_arguments_are_paths(bad, tmp_path):
    """Audit of issue 13: an int path was taken for a file descriptor (``path=True`` read
    or wrote, then closed, the process's stdout); a path is a str or os.PathLike."""
    with pytest.raises(TypeError, match="path"):
        read_q_stream_csv(bad)
    with pytest.raises(TypeError, match="path"):
        motion_io.write_text_atomic(bad, "x")

"""The rebuild changes no result: the public API against the outputs stored at 6c198b4.

``tests/_golden.py`` says which calls; ``scripts/golden.py --write`` stored the values.
Arrays agree to 1e-12, the URDF/MJCF texts and the MCAP file's bytes exactly.
"""

from __future__ import annotations

import _golden


def test_golden_outputs_unchanged():
    values = _golden.compute()
    bad = _golden.mismatches(values, _golden.load())
    assert not bad, "\n".join(bad)


def test_golden_mismatch_is_reported():
    # the comparison itself can fail: a changed array, a changed text, a missing value
    stored = _golden.load()
    values = dict(stored)
    values["fk.p"] = stored["fk.p"] + 1e-9
    values["urdf"] = stored["urdf"] + " "
    del values["mjcf"]
    bad = _golden.mismatches(values, stored)
    assert any(b.startswith("fk.p") for b in bad)
    assert any(b.startswith("urdf") for b in bad)
    assert "missing: mjcf" in bad

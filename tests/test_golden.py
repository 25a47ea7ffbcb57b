"""The rebuild changes no result: the public API against the outputs stored at 6c198b4.

``tests/_golden.py`` says which calls; ``scripts/golden.py --write`` stored the values.
Arrays agree to 1e-12 of their scale, the URDF/MJCF texts as parsed documents (their
numbers to 1e-14 of each attribute's scale, ``tests/_golden.py``), other texts exactly.
"""

from __future__ import annotations

import re

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
    values["urdf"] = stored["urdf"].replace('name="', 'name="x', 1)
    del values["mjcf"]
    bad = _golden.mismatches(values, stored)
    assert any(b.startswith("fk.p") for b in bad)
    assert any(b.startswith("urdf") for b in bad)
    assert "missing: mjcf" in bad


def test_golden_texts_compare_as_documents():
    # a last-digit change of a printed float (another CPU's rounding) is no difference;
    # a change of a number beyond 1e-14 of its attribute's scale, or of a name, is
    stored = _golden.load()
    urdf = stored["urdf"]
    m = re.search(r'xyz="([-0-9.e]+) ', urdf)
    assert m, "the URDF has an xyz attribute"
    x = float(m.group(1))
    bumped = lambda f: urdf[:m.start(1)] + repr(f) + urdf[m.end(1):]  # noqa: E731
    scale = max(abs(float(v)) for v in urdf[m.start(1):].split('"')[0].split())
    assert not _golden.mismatches({**stored, "urdf": bumped(x + 2e-16 * scale)}, stored)
    assert _golden.mismatches({**stored, "urdf": bumped(x + 1e-12 * scale + 1e-12)}, stored)

"""The body vocabulary and the batched mechanism points (athenakin._mechanism)."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin._mechanism import (
    BODIES,
    BODY_JOINTS,
    BODY_SEGMENTS,
    POINT_NAMES,
    BodyGeometry,
    adjacent_pairs,
    body_segments,
    mechanism_points,
)
from athenakin.errors import InvalidInputError
from athenakin.robot import REFERENCE_Q


@pytest.fixture(scope="module")
def setup():
    d = ak.Design.default()
    T = ak.default_rcm_frame(d)
    rng = np.random.default_rng(7)
    q = REFERENCE_Q + rng.uniform(-0.03, 0.03, (200, 3))
    return d, T, q


def test_table_names_are_closed():
    for a, b in BODY_SEGMENTS.values():
        assert a in POINT_NAMES and b in POINT_NAMES
    for members in BODY_JOINTS.values():
        assert set(members) <= set(BODIES)
    order = {b: i for i, b in enumerate(BODIES)}
    assert all(order[a] < order[b] for a, b in adjacent_pairs())


def test_segment_lengths_are_the_design_lengths(setup):
    d, T, q = setup
    mp = mechanism_points(q, T, d, slot="all")
    seg = body_segments(mp)
    L = np.linalg.norm(seg[..., 1, :] - seg[..., 0, :], axis=-1)
    v = mp.valid
    assert v.sum() > 1000
    want = {"link_a": d.l1, "link_b": d.l1, "link_ad": d.l3, "link_bd": d.l3,
            "carrier": np.hypot(d.l2, d.l5), "platform": d.l4, "instrument": d.tool_length}
    for name, length in want.items():
        assert_allclose(L[v][:, BODIES.index(name)], length, rtol=0, atol=1e-12)
    qq = np.broadcast_to(q[:, None, :], v.shape + (3,))
    assert_allclose(L[v][:, BODIES.index("actuator")], qq[v][:, 2], rtol=0, atol=1e-12)
    # the spherical mechanism's ends lie at sphere_radius from the RCM, the guide on the axis
    r = np.linalg.norm(mp["S_4"] - mp["RCM"], axis=-1)
    assert_allclose(r[v], BodyGeometry().sphere_radius, rtol=0, atol=1e-12)
    assert np.isnan(mp.xyz[~v]).all()


def test_slot_equals_slice_of_all(setup):
    d, T, q = setup
    allm = mechanism_points(q[:20], T, d, slot="all")
    for k in (0, 5, 15):
        one = mechanism_points(q[:20], T, d, slot=k)
        assert_allclose(one.xyz, allm.xyz[:, k], rtol=0, atol=0, equal_nan=True)


@pytest.mark.parametrize("slot", [16, -1, 1.5, True, "any"])
def test_bad_slot(slot):
    d = ak.Design.default()
    with pytest.raises(InvalidInputError, match="slot"):
        mechanism_points(REFERENCE_Q, ak.default_rcm_frame(d), d, slot=slot)


@pytest.mark.parametrize("field, value", [("sphere_radius", -0.1), ("carriage_length", np.nan),
                                          ("rail_margin", np.inf)])
def test_bad_geometry(field, value):
    with pytest.raises((InvalidInputError, ValueError), match=field):
        BodyGeometry(**{field: value})


def test_sphere_link_points_are_continuous(setup):
    """S_4 follows the u4 axis continuously: no flip with the rounding of a zero dot product."""
    d, T, q = setup
    t = np.linspace(0.0, 1.0, 201)[:, None]
    path = q[0] + t * (q[1] - q[0])
    mp = mechanism_points(path, T, d, slot=0)
    for name in ("S_3", "S_4", "S_5"):
        step = np.linalg.norm(np.diff(mp[name], axis=0), axis=-1)
        assert step.max() < 0.01, name

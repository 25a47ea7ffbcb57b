"""The mass model (athenakin.dynamics.MassModel): constructors, TOML round trip, errors."""

import math
import types

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin._mechanism import BODIES
from athenakin.dynamics import (
    MASS_BODIES,
    REFERENCE_MASSES,
    MassModel,
    actuator_part_length,
    body_segment_in_frame,
)
from athenakin.errors import InvalidInputError

D = ak.Design.default()


def test_names_extend_the_one_vocabulary():
    assert MASS_BODIES[:len(BODIES)] == BODIES
    assert set(MASS_BODIES) - set(BODIES) == {"slider_d", "actuator_rod", "guide"}


def test_slender_rod_of_link_a():
    m = MassModel.slender_rods({"link_a": 0.35}, D)
    mass, com, inertia = m.body("link_a")
    assert mass == 0.35
    assert_allclose(com, [0, 0, D.l1 / 2], rtol=0, atol=1e-15)
    assert_allclose(inertia, np.diag([0.35 * D.l1 ** 2 / 12] * 2 + [0.0]), rtol=0, atol=1e-15)
    others = [b for b in MASS_BODIES if b != "link_a"]
    assert all(m.body(b)[0] == 0 for b in others)
    assert m.total_mass == 0.35


def test_slender_rod_across_the_carrier_and_point_masses():
    m = MassModel.slender_rods({"carrier": 0.4, "guide": 0.05, "actuator_rod": 0.2}, D)
    _, com, inertia = m.body("carrier")
    u = np.array([0, D.l2, D.l5])
    L2 = u @ u
    assert_allclose(com, u / 2, rtol=0, atol=1e-15)
    assert_allclose(inertia @ u, 0, rtol=0, atol=1e-15)               # none about its axis
    assert_allclose(np.trace(inertia), 2 * 0.4 * L2 / 12, rtol=1e-14, atol=0)
    assert_allclose(m.body("guide")[2], 0, atol=0)
    a = actuator_part_length(D)
    assert a == 0.5 * D.stroke_min[2]
    assert_allclose(m.body("actuator_rod")[1], [0, 0, -a / 2], rtol=0, atol=1e-16)


def test_from_bodies_solid_capsules_with_a_stand_in():
    bodies = types.SimpleNamespace(radius={"link_b": 0.01, "actuator": 0.02, "instrument": 0.0})
    rho = 2700.0
    m = MassModel.from_bodies(bodies, density=rho, design=D)
    mass, com, inertia = m.body("link_b")
    r, L = 0.01, D.l1
    assert_allclose(mass, rho * (math.pi * r * r * L + 4 / 3 * math.pi * r ** 3), rtol=1e-14)
    assert_allclose(com, [0, 0, L / 2], rtol=0, atol=1e-15)
    m_cyl = rho * math.pi * r * r * L
    m_s = rho * 4 / 3 * math.pi * r ** 3
    assert_allclose(inertia[2, 2], m_cyl * r * r / 2 + m_s * 2 * r * r / 5, rtol=1e-12)
    # the actuator's radius makes both rigid parts, each of actuator_part_length
    a = actuator_part_length(D)
    for part in ("actuator", "actuator_rod"):
        assert_allclose(m.body(part)[0], rho * (math.pi * 0.02 ** 2 * a
                                                + 4 / 3 * math.pi * 0.02 ** 3), rtol=1e-14)
    assert m.body("instrument")[0] == 0.0
    assert m.body("link_a")[0] == 0.0


def test_from_bodies_rejects_what_has_no_radius_map():
    with pytest.raises(TypeError, match="bodies: expected an object with a mapping .radius"):
        MassModel.from_bodies(object(), density=1.0)
    with pytest.raises(InvalidInputError, match="unknown body 'wheel'"):
        MassModel.from_bodies(types.SimpleNamespace(radius={"wheel": 0.1}), density=1.0)
    with pytest.raises(InvalidInputError, match="radius"):
        MassModel.from_bodies(types.SimpleNamespace(radius={"link_a": -0.1}), density=1.0)


def test_reference_model():
    m = MassModel.reference()
    assert_allclose(m.total_mass, sum(REFERENCE_MASSES.values()), rtol=1e-15)
    for name, mass in REFERENCE_MASSES.items():
        assert m.body(name)[0] == mass


def test_toml_round_trip_beside_the_design(tmp_path):
    m = MassModel.reference()
    rng = np.random.default_rng(3)
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    mapping = m.to_mapping()
    mapping["platform"]["inertia"] = (R @ np.diag([1e-3, 2e-3, 2.5e-3]) @ R.T).tolist()
    mapping["platform"]["com"] = [0.001, -0.002, 0.07]
    m2 = MassModel.from_mapping(mapping)
    path = tmp_path / "design.toml"
    path.write_text(D.to_toml() + "\n" + m2.to_toml())
    assert MassModel.from_toml(path) == m2
    assert ak.Design.from_toml(path) == D


@pytest.mark.parametrize("data, match", [
    ({"link_a": {"mass": -1.0}}, "expected a mass in"),
    ({"link_a": {"mass": float("nan")}}, "finite"),
    ({"wheel": {"mass": 1.0}}, "unknown body 'wheel'"),
    ({"link_a": {"mass": 1.0, "colour": "red"}}, "unknown key"),
    ({"link_a": {"com": [0, 0, 0]}}, "missing 'mass'"),
    ({"link_a": {"mass": 1.0, "inertia": [[1, 0, 0], [0, 1, 0], [0, 0, -1]]}},
     "positive semidefinite"),
    ({"link_a": {"mass": 1.0, "inertia": [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]}}, "symmetric"),
    ({"link_a": {"mass": 1.0, "inertia": [[1, 0, 0], [0, 1, 0], [0, 0, 3]]}}, "triangle"),
    ({"link_a": {"mass": 0.0, "inertia": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}}, "massless"),
    ({"link_a": {"mass": 1.0, "com": [0, 0]}}, "shape"),
])
def test_bad_tables_raise_named_errors(data, match):
    with pytest.raises(InvalidInputError, match=match):
        MassModel.from_mapping(data)


def test_bad_slender_rods_and_toml(tmp_path):
    with pytest.raises(InvalidInputError, match=r"masses\['link_a'\]: expected a mass >= 0"):
        MassModel.slender_rods({"link_a": -0.1})
    with pytest.raises(InvalidInputError, match="unknown body"):
        MassModel.slender_rods({"tool": 0.1})
    with pytest.raises(TypeError, match="masses: expected a mapping"):
        MassModel.slender_rods([0.1])  # type: ignore[arg-type]
    f = tmp_path / "d.toml"
    f.write_text(D.to_toml())
    with pytest.raises(InvalidInputError, match=r"expected a \[masses\] table"):
        MassModel.from_toml(f)
    with pytest.raises(InvalidInputError, match="name: unknown body"):
        MassModel.reference().body("nope")
    with pytest.raises(InvalidInputError, match="name: expected one of"):
        body_segment_in_frame("nope")


def test_model_is_frozen_and_read_only():
    m = MassModel.reference()
    with pytest.raises(ValueError):
        m.mass[0] = 1.0
    with pytest.raises(AttributeError):
        m.mass = np.zeros(len(MASS_BODIES))  # type: ignore[misc]


def test_from_bodies_takes_the_geometry_of_the_bodies():
    from athenakin._mechanism import BodyGeometry

    g = BodyGeometry(sphere_radius=0.2)
    bodies = types.SimpleNamespace(radius={"sphere_link_1": 0.005}, geometry=g)
    m = MassModel.from_bodies(bodies, density=1000.0, design=D)
    seg = body_segment_in_frame("sphere_link_1", D, g)
    assert_allclose(np.linalg.norm(seg[1] - seg[0]), 0.2 * math.sqrt(2), rtol=1e-15)
    assert_allclose(m.body("sphere_link_1")[1], seg.mean(axis=0), rtol=0, atol=1e-15)

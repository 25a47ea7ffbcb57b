"""InverseDynamicsLoop: the numbers of inverse_dynamics, one state at a time, never raising."""

from __future__ import annotations

import numpy as np
import pytest

import athenakin as ak
from athenakin import _backend, dynamics, sim
from athenakin.errors import InvalidInputError

D = ak.Design.default()
T = ak.default_rcm_frame(D)
RNG = np.random.default_rng(29)
BACKENDS = ["numpy", pytest.param("numba", marks=pytest.mark.skipif(
    not _backend.numba_available(), reason="numba not available here"))]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("slot", [0, 3, 9])
def test_loop_equals_inverse_dynamics(backend, slot):
    q = sim.sample_reachable_q(20, T, D, slot=slot, rng=RNG)
    qd = RNG.normal(0, 0.05, q.shape)
    qdd = RNG.normal(0, 0.5, q.shape)
    masses = dynamics.MassModel.reference(D)
    g = (0.3, -0.2, -9.7)
    loop = dynamics.InverseDynamicsLoop(T, D, masses=masses, gravity=g, slot=slot,
                                        backend=backend)
    assert loop.compiled == (backend == "numba")
    want = dynamics.inverse_dynamics(q, qd, qdd, T, D, masses=masses, gravity=g, slot=slot,
                                     backend=backend)
    got = np.array([loop(a, b, c).copy() for a, b, c in zip(q, qd, qdd, strict=True)])
    np.testing.assert_array_equal(got, want)       # the same kernel on the same inputs


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_state_that_does_not_assemble_gives_nan_not_an_error(backend):
    loop = dynamics.InverseDynamicsLoop(T, D, backend=backend)
    f = loop([0.5, -0.5, 0.45], np.zeros(3), np.zeros(3))   # A and B swapped: no assembly
    assert np.isnan(f).all()
    f = loop([np.nan, 0.1, 0.45], np.zeros(3), np.zeros(3))
    assert np.isnan(f).all()
    # and the loop goes on afterwards
    ok = loop([-0.1, 0.1, 0.45], np.zeros(3), np.zeros(3))
    np.testing.assert_allclose(ok, dynamics.inverse_dynamics([-0.1, 0.1, 0.45], np.zeros(3),
                                                             np.zeros(3)), rtol=0, atol=1e-12)


@pytest.mark.parametrize("kw, err, match", [
    ({"slot": 16}, InvalidInputError, "slot"),
    ({"gravity": (0.0, np.nan, -9.8)}, InvalidInputError, "gravity"),
    ({"gravity": np.zeros((2, 3))}, ValueError, "gravity"),
    ({"masses": "reference"}, TypeError, "masses"),
    ({"backend": "gpu"}, ValueError, "backend"),
])
def test_bad_set_up_is_named_once(kw, err, match):
    with pytest.raises(err, match=match):
        dynamics.InverseDynamicsLoop(T, D, **kw)


def test_batch_of_frames_is_refused():
    with pytest.raises((ValueError, InvalidInputError), match="T_b_e"):
        dynamics.InverseDynamicsLoop(np.stack([T, T]), D)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("bad, name", [
    ((np.zeros((3, 1)), "qd"), "qd"),          # a column: numpy's broadcast error before
    ((0.0, "qd"), "qd"),                       # a scalar: broadcast silently before
    ((np.zeros((1, 3)), "qdd"), "qdd"),
    ((["a", "b", "c"], "q"), "q"),
])
def test_a_wrong_shape_or_type_is_a_named_error(backend, bad, name):
    loop = dynamics.InverseDynamicsLoop(T, D, backend=backend)
    args = {"q": [-0.1, 0.1, 0.45], "qd": np.zeros(3), "qdd": np.zeros(3)}
    args[bad[1]] = bad[0]
    with pytest.raises(InvalidInputError, match=rf"\b{name}\b"):
        loop(args["q"], args["qd"], args["qdd"])


@pytest.mark.parametrize("backend", BACKENDS)
def test_nan_exactly_where_inverse_dynamics_flags(backend):
    """The singular set |h| = l3 and states off the slot: NaN in both, the same elsewhere."""
    h = D.l3                                   # |q1 - q2| / 2 = l3: the carriage on the rail
    qs = np.array([[-h, h, 0.45], [-h + 1e-9, h - 1e-9, 0.45], [-0.1, 0.1, 0.45],
                   [-0.1, 0.1, 5.0], [0.5, -0.5, 0.45]])
    qd = np.tile([0.01, -0.02, 0.03], (len(qs), 1))
    qdd = np.tile([0.1, 0.2, -0.3], (len(qs), 1))
    loop = dynamics.InverseDynamicsLoop(T, D, backend=backend)
    want = dynamics.inverse_dynamics(qs, qd, qdd, T, D, errors="flag", backend=backend)
    got = np.array([loop(a, b, c).copy() for a, b, c in zip(qs, qd, qdd, strict=True)])
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
    ok = ~np.isnan(want)
    np.testing.assert_allclose(got[ok], want[ok], rtol=1e-12, atol=0)
    assert np.isnan(want).any()
    assert np.isnan(loop([-0.1, 0.1, np.inf], qd[0], qdd[0])).all()   # the function refuses it


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("slot", [0, 5, 8, 13])
def test_plain_float_tuples_give_the_array_numbers_bit_for_bit(backend, slot):
    """A control loop's tuples of floats (the compiled path takes them without a
    conversion) and arrays, lists, tuples of ints or numpy scalars: the same forces,
    and inverse_dynamics' flags, on states that assemble and states that do not."""
    rng = np.random.default_rng(slot + 101)
    q = np.concatenate([sim.sample_reachable_q(15, T, D, slot=slot, rng=rng),
                        rng.uniform([-0.3, -0.3, 0.0], [0.3, 0.3, 0.8], (15, 3)),
                        [[np.nan, 0.1, 0.45], [-D.l3, D.l3, 0.45]]])
    qd = rng.normal(0, 0.05, q.shape)
    qdd = rng.normal(0, 0.5, q.shape)
    loop = dynamics.InverseDynamicsLoop(T, D, slot=slot, backend=backend)
    want = np.full(q.shape, np.nan)                    # the function refuses a NaN q
    fin = np.isfinite(q).all(axis=1)
    want[fin] = dynamics.inverse_dynamics(q[fin], qd[fin], qdd[fin], T, D, slot=slot,
                                          errors="flag", backend=backend)
    assert np.isnan(want).any() and not np.isnan(want).all()
    for a, b, c, w in zip(q, qd, qdd, want, strict=True):
        forms = [(tuple(a.tolist()), tuple(b.tolist()), tuple(c.tolist())), (a, b, c),
                 (list(a), list(b), list(c)), (tuple(a), tuple(b), tuple(c))]  # np.float64
        for args in forms:
            np.testing.assert_array_equal(loop(*args), w)
    f = loop((-0.1, 0.1, 0.45), (0, 0, 0), (0.0, 0.0, 0.0))           # ints: numbers
    np.testing.assert_array_equal(f, loop(np.array([-0.1, 0.1, 0.45]), np.zeros(3),
                                          np.zeros(3)))
    with pytest.raises(InvalidInputError, match=r"\bqd\b"):
        loop((-0.1, 0.1, 0.45), (0.0, 0.0), (0.0, 0.0, 0.0))         # a short tuple
    with pytest.raises(InvalidInputError, match=r"\bqdd\b"):
        loop((-0.1, 0.1, 0.45), (0.0, 0.0, 0.0), (0.0, 0.0, "x"))

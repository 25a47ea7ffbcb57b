"""Force figures near the singular set q1 = q2: flagged by the guards' conditioning margin."""

from __future__ import annotations

import math

import numpy as np
import pytest

import athenakin as ak
from athenakin.dynamics import (
    COND_MARGIN,
    force_capability,
    force_metrics,
    tip_condition_number,
)
from athenakin.motion import Margins

D = ak.Design.default()
T = ak.default_rcm_frame(D)


def _gap(gap):
    """Configurations with q2 - q1 = gap about q1 = -0.1 m, q3 = 0.45 m."""
    gap = np.atleast_1d(gap)
    return np.stack([-0.1 - gap / 2, -0.1 + gap / 2, np.full(gap.shape, 0.45)], axis=-1)


def test_the_margin_is_the_tracker_and_teleop_one():
    assert COND_MARGIN == Margins().cond


@pytest.mark.parametrize("gap", [1e-2, 1e-4, 1e-7])
def test_a_near_singular_configuration_gives_no_peak_force(gap):
    fm = force_metrics(_gap(gap), T, D, slot=0)
    assert math.isnan(fm.peak_actuator_force)
    assert (fm.n_valid, fm.n_peak, fm.n_near_singular) == (1, 0, 1)
    # the figure left out is absurd, not rounding: it grows as cond^3
    raw = force_metrics(_gap(gap), T, D, slot=0, cond_max=math.inf)
    assert raw.peak_actuator_force > 1e3 and raw.n_near_singular == 0


def test_far_from_the_singular_set_nothing_changes():
    q = _gap(np.array([0.2, 0.1, 0.03]))
    fm = force_metrics(q, T, D, slot=0)
    raw = force_metrics(q, T, D, slot=0, cond_max=math.inf)
    assert fm == raw and fm.n_near_singular == 0 and 0 < fm.peak_actuator_force < 1e3


def test_a_set_keeps_its_well_conditioned_peak():
    q = _gap(np.array([0.2, 1e-7]))
    fm = force_metrics(q, T, D, slot=0)
    alone = force_metrics(q[:1], T, D, slot=0)
    assert fm.peak_actuator_force == alone.peak_actuator_force
    assert (fm.n_valid, fm.n_peak, fm.n_near_singular) == (2, 1, 1)


def test_capability_carries_the_conditioning_and_the_flag():
    gaps = np.array([0.2, 0.03, 1e-2, 1e-7])
    cap = force_capability(_gap(gaps), T, D, f_max=50.0, errors="flag")
    assert cap.valid.all()
    J = np.swapaxes(cap.A[:, :3], -1, -2)
    np.testing.assert_allclose(cap.cond, np.linalg.cond(J), rtol=1e-9)
    np.testing.assert_array_equal(cap.near_singular, cap.cond > COND_MARGIN)
    np.testing.assert_array_equal(cap.near_singular, [False, False, True, True])
    # the conditioning grows as 1 / gap toward q1 = q2
    assert cap.cond[3] > 1e6
    off = force_capability(_gap(gaps), T, D, f_max=50.0, errors="flag", cond_max=math.inf)
    assert not off.near_singular.any()


def test_tip_condition_number_is_inf_where_singular():
    J = np.array([np.eye(3), [[1.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 0.0]]])
    np.testing.assert_allclose(tip_condition_number(J), [1.0, np.inf])


@pytest.mark.parametrize("bad", [0.5, math.nan, -1.0])
def test_cond_max_below_one_is_refused_by_name(bad):
    with pytest.raises(ValueError, match=r"\bcond_max\b"):
        force_metrics(_gap(0.2), T, D, slot=0, cond_max=bad)


def test_cond_max_of_the_wrong_type_is_a_named_type_error():
    with pytest.raises(TypeError, match=r"^cond_max: "):
        force_capability(_gap(0.2), T, D, f_max=50.0, cond_max="100")

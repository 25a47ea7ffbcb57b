"""athenakin.calibration: statistics of the estimates and accuracy analysis (seeded)."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

import athenakin as ak
from athenakin import calibration as cal

D = ak.Design.default()
T = ak.default_rcm_frame(D)
NOISE = 20e-6


def truth(data, names):
    return np.array([data.true_parameters[n] for n in names])


@pytest.mark.parametrize("params, kw", [
    (None, {}),
    (["default", "offsets"], {"offset_std": 3e-4}),
    (None, {"frame": "tracker"}),
])
def test_z_scores_over_30_seeds_are_standard_normal(params, kw):
    """20 um noise, 80 poses: (estimate - truth) / std ~ N(0, 1) pooled over 30 seeds."""
    z = []
    for seed in range(30):
        data = cal.synthetic_measurements(
            T, D, n=80, rng=1000 + seed, frame=kw.get("frame", "base"),
            options=cal.SyntheticOptions(noise=NOISE, offset_std=kw.get("offset_std", 0.0)))
        res = cal.calibrate(data.q, data.tips, T, D, params=params,
                            frame=kw.get("frame", "base"))
        robot = [i for i, n in enumerate(res.names) if not n.startswith("reg_")]
        names = [res.names[i] for i in robot]
        z.append((res.estimates[robot] - truth(data, names)) / res.std[robot])
        assert abs(res.sigma / NOISE - 1) < 0.25
    z = np.concatenate(z)
    assert np.mean(np.abs(z) < 3) >= 0.98          # "every estimate within 3 sigma"
    assert np.max(np.abs(z)) < 4.5
    assert abs(np.mean(z)) < 3 / np.sqrt(z.size)   # 3 sigma of the mean
    assert 0.8 < np.std(z) < 1.2


TRUE = {"l1": 0.3004, "l2": 0.0997, "l3": 0.2496, "l4": 0.1502, "l5": 0.4003,
        "tool_length": 0.4505, "q1_offset": 2e-4, "q2_offset": -1e-4, "q3_offset": 3e-4}


@pytest.mark.filterwarnings("ignore::athenakin.calibration.CalibrationWarning")
def test_reported_covariance_matches_monte_carlo_over_noise():
    """Same robot, same poses, 150 noise draws: the spread of the estimates is the covariance."""
    q = cal.random_poses(80, T, D, rng=7)
    est, covs = [], []
    for seed in range(150):
        data = cal.synthetic_measurements(T, D, q=q, rng=np.random.default_rng([7, seed]),
                                          options=cal.SyntheticOptions(
                                              noise=NOISE, perturbation=0.0, true=TRUE))
        res = cal.calibrate(data.q, data.tips, T, D, params=["default", "offsets"])
        est.append(res.estimates)
        covs.append(res.covariance)
    est = np.array(est)
    assert np.all(np.abs(est.mean(axis=0) - list(TRUE.values())) < 4 * np.sqrt(
        np.diag(np.mean(covs, axis=0)) / len(est)))   # unbiased
    emp = np.cov(est.T)
    rep = np.mean(covs, axis=0)
    ratio = np.sqrt(np.diag(emp) / np.diag(rep))
    assert np.all((ratio > 0.8) & (ratio < 1.2)), ratio      # std of a std: 6 % here
    corr_e = emp / np.sqrt(np.outer(np.diag(emp), np.diag(emp)))
    corr_r = rep / np.sqrt(np.outer(np.diag(rep), np.diag(rep)))
    assert np.max(np.abs(corr_e - corr_r)) < 0.25


def test_first_order_tip_error_matches_monte_carlo():
    data = cal.synthetic_measurements(T, D, n=40, rng=8,
                                      options=cal.SyntheticOptions(noise=NOISE, offset_std=3e-4))
    res = cal.calibrate(data.q, data.tips, T, D, params=["default", "offsets"])
    q = cal.random_poses(6, T, D, rng=9)
    for resolution in (0.0, 20e-6):
        te = cal.tip_error(res, q, encoder_resolution=resolution)
        mc = cal.tip_error_monte_carlo(res, q, encoder_resolution=resolution, n_samples=3000,
                                       rng=10)
        # 3000 samples: relative error of a variance about sqrt(2 / 3000) = 2.6 %
        assert_allclose(np.trace(mc, axis1=1, axis2=2), te.rms ** 2, rtol=0.12)
        scale = np.max(np.abs(te.covariance), axis=(1, 2))[:, None, None]
        assert np.max(np.abs(mc - te.covariance) / scale) < 0.12
    te = cal.tip_error(res, q, encoder_resolution=20e-6)
    assert_allclose(te.covariance, te.from_parameters + te.from_encoders, rtol=1e-12)
    assert np.all(te.rms > np.sqrt(np.trace(te.from_parameters, axis1=1, axis2=2)))


def test_tip_error_map_over_the_cone():
    data = cal.synthetic_measurements(T, D, n=40, rng=11,
                                      options=cal.SyntheticOptions(noise=NOISE))
    res = cal.calibrate(data.q, data.tips, T, D)
    m = cal.tip_error_map(res, resolution=(24, 13), encoder_resolution=10e-6)
    assert m.rms.shape == (24, 13) and m.q.shape == (24, 13, 3)
    ok = np.isfinite(m.rms)
    assert 0 < np.sum(ok) < ok.size
    assert np.all(np.isnan(m.q[~ok]))
    i, j = np.argwhere(ok)[0]
    direct = cal.tip_error(res, m.q[i, j][None], encoder_resolution=10e-6).rms[0]
    assert m.rms[i, j] == pytest.approx(direct, rel=1e-12)
    # the reading reaches the commanded tip with the calibrated model
    pr = cal._model.predict(np.array([res.parameters[n] for n in cal.PARAMETERS]),
                            m.q[i, j][None], np.ones(1))
    assert np.linalg.norm(pr.tip_base[0] - res.rcm) == pytest.approx(m.depth, abs=1e-12)
    with pytest.raises(ak.InvalidInputError, match="depth"):
        cal.tip_error_map(res, depth=1.0)


def test_d_optimal_plan_gives_smaller_standard_deviations():
    params = ["default", "offsets"]
    plan = cal.plan_poses(30, T, D, params=params, n_candidates=800, rng=12)
    rnd = cal.random_poses(30, T, D, rng=13)
    noise = cal.SyntheticOptions(noise=NOISE, offset_std=3e-4, true={"l2": 0.1003})
    res_p = cal.calibrate(*(lambda d: (d.q, d.tips))(cal.synthetic_measurements(
        T, D, q=plan.q, rng=14, options=noise)), T, D, params=params)
    res_r = cal.calibrate(*(lambda d: (d.q, d.tips))(cal.synthetic_measurements(
        T, D, q=rnd, rng=14, options=noise)), T, D, params=params)
    # the determinant (product of the std devs, roughly) is what the plan optimises
    assert np.sum(np.log(res_p.std)) < np.sum(np.log(res_r.std))

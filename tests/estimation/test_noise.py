import numpy as np
import pytest

from oceanloc.errors import DataError
from oceanloc.estimation.noise import (
    running_range_noise,
    stationary_mask,
    stationary_range_noise,
    stationary_segments,
    total_range_sigma_m,
)


def test_running_estimates_match_numpy_and_converge():
    # 250 stationary ranges as in the papers: sigma_hat has relative SE 1/sqrt(2*249) = 4.5%; allow 3 SE.
    rng = np.random.default_rng(30)
    r = 9.02 + 0.113 * rng.standard_normal(250)
    est = running_range_noise(r)
    np.testing.assert_allclose(est.range_m[-1], r.mean(), rtol=1e-12)
    np.testing.assert_allclose(
        est.sigma_m[1:], [np.std(r[: i + 1], ddof=1) for i in range(1, 250)], rtol=1e-9
    )
    assert abs(est.final_sigma_m / 0.113 - 1) < 3 * 0.045
    assert np.isnan(est.sigma_m[0])


def test_total_sigma_is_the_journal_value_and_bad_input_errors():
    assert total_range_sigma_m(0.113, 1.0) == pytest.approx(1.006, abs=5e-4)
    with pytest.raises(DataError):
        running_range_noise([1.0])
    with pytest.raises(DataError, match="NaN"):
        running_range_noise([1.0, np.nan, 2.0])


def test_stationary_mask_finds_the_still_segment():
    t = np.arange(600.0)
    pos = np.zeros((600, 3))
    pos[300:, 0] = np.arange(300) * 1.0  # moving at 1 m/s after 300 s
    still = stationary_mask(t, pos + 0.3 * np.random.default_rng(0).standard_normal((600, 3)))
    assert still[:280].all() and not still[320:].any()


def test_stationary_segments_keep_only_long_stretches():
    t = np.arange(1000.0)
    still = np.zeros(1000, dtype=bool)
    still[0:400] = True  # a 399 s hold
    still[500:530] = True  # a 29 s hover: too short
    still[700:900] = True
    seg = stationary_segments(t, still, min_duration_s=120.0)
    assert set(np.unique(seg)) == {-1, 0, 1}
    assert np.all(seg[0:400] == 0) and np.all(seg[700:900] == 1) and np.all(seg[500:530] == -1)


def test_noise_on_simulated_pier_logs_recovers_the_usbl_sigmas(tmp_path):
    # 6 seeded pier logs (62 and 113 mm, 5 % multipath of +5..+30 m): each stationary set has ~125 ranges,
    # so sigma_hat has relative SE 1/sqrt(2*124) = 6.3 % and the mean of 6 has 2.6 %; the one-at-a-time
    # 3-sigma trim biases it low by ~1.3 % (a normal truncated at 3 sigma) to ~4 % (measured over 12
    # seeds). Accept 0.88 to 1.05 of the truth for the mean, and every multipath return removed.
    from oceanloc.io.nmea import read_nmea
    from oceanloc.io.usbl import align_ranges, read_usbl
    from oceanloc.sim.logs import PierLogSettings, simulate_pier_logs

    sigmas = []
    for seed in range(6):
        logs = simulate_pier_logs(tmp_path / str(seed), PierLogSettings(), np.random.default_rng(seed))
        a = align_ranges(read_nmea(logs.nmea_path), read_usbl(logs.ranges_path))
        seg = stationary_segments(a.t_unix_s, stationary_mask(a.t_unix_s, a.vehicle_enu_m))
        est = stationary_range_noise(a.t_unix_s, a.beacon, a.range_m, seg)
        assert [e.beacon for e in est] == [1, 2]
        for e in est:
            kept = e.running.range_m.size
            assert kept + e.n_outliers == e.n_ranges
        sigmas.append([e.sigma_m for e in est])
    ratio = np.mean(sigmas, axis=0) / np.array([0.062, 0.113])
    assert np.all((ratio > 0.88) & (ratio < 1.05)), ratio
    assert total_range_sigma_m(max(np.mean(sigmas, axis=0)), 1.0) == pytest.approx(1.006, abs=0.002)


def test_stationary_noise_rejects_mismatched_inputs():
    with pytest.raises(DataError, match="differ in length"):
        stationary_range_noise(np.arange(3.0), np.ones(3), np.ones(3), np.zeros(2, dtype=int))

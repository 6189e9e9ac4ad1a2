import numpy as np
import pytest

from oceanloc.planning.information import (
    information_gain,
    information_gain_reference,
    log_det_information,
    scaled_cholesky,
)
from oceanloc.planning.random_problems import random_planning_states


@pytest.mark.parametrize("k", [1, 2, 3, 4])
@pytest.mark.parametrize("m", [1, 4])
def test_fast_gain_equals_eq29_log_det(k, m):
    rng = np.random.default_rng(k * 10 + m)
    st = random_planning_states(rng, 5, m)
    sites = np.column_stack([rng.uniform(-20, 20, (k, 2)), np.zeros(k)])
    chol = scaled_cholesky(st.covariances_m2, 0.12)
    fast = information_gain(np.broadcast_to(sites, (5, k, 3)), st.estimates_m, chol)
    for b in range(5):
        ref = information_gain_reference(sites, st.estimates_m[b], st.covariances_m2[b], 0.12)
        assert fast[b] == pytest.approx(ref, rel=1e-9, abs=1e-9)


def test_single_step_gain_is_log_one_plus_alpha_with_sigma():
    # Conference eq. (25) with the sigma^-2 the journal's eq. (37) omits: alpha = h P h^T / sigma^2.
    cov = np.diag([4.0, 1.0, 0.25])
    est = np.array([10.0, 0.0, -5.0])
    site = np.zeros(3)
    h = (est - site) / np.linalg.norm(est - site)
    alpha = h @ cov @ h / 0.1**2
    gain = information_gain(site[None, :], est[None, :], scaled_cholesky(cov[None], 0.1))
    assert gain == pytest.approx(np.log1p(alpha), rel=1e-12)


def test_block_diagonal_log_det_is_sum_over_transponders():
    rng = np.random.default_rng(0)
    blocks = [np.linalg.inv(c) for c in random_planning_states(rng, 1, 4).covariances_m2[0]]
    full = np.zeros((12, 12))
    for i, b in enumerate(blocks):
        full[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = b
    assert log_det_information(np.array(blocks)).sum() == pytest.approx(np.linalg.slogdet(full)[1], rel=1e-12)


def test_closed_form_log_det_matches_slogdet_and_refuses_four_rows():
    from oceanloc.errors import ConfigError
    from oceanloc.planning.information import log_det_identity_plus_gram

    u = np.random.default_rng(4).normal(size=(3, 3, 10))  # rows, components, batch
    for k in (1, 2, 3):
        U = np.moveaxis(u[:k], -1, 0)  # (10, k, 3)
        expected = np.linalg.slogdet(np.eye(k) + U @ np.swapaxes(U, 1, 2))[1]
        np.testing.assert_allclose(
            log_det_identity_plus_gram([tuple(r) for r in u[:k]]), expected, rtol=1e-12
        )
    with pytest.raises(ConfigError, match="1 to 3 rows"):
        log_det_identity_plus_gram([tuple(u[0])] * 4)


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_look_ahead_objective_equals_eq29_at_the_rolled_out_sites(k):
    from oceanloc.models.vehicles import unicycle_rollout
    from oceanloc.planning.measurement_sites import LookaheadPlanner

    rng = np.random.default_rng(40 + k)
    st = random_planning_states(rng, 4, 4)
    planner = LookaheadPlanner(
        horizon=k, max_yaw_rate_rad_s=0.5, speed_mps=3.0, period_s=1.0, sigma_range_m=0.12
    )
    rates = rng.uniform(-0.5, 0.5, (4, 6, k))
    gain = planner.gain(st, rates)
    for b in range(4):
        for c in range(6):
            poses = unicycle_rollout(
                st.pos_enu_m[b : b + 1], st.yaw_rad[b : b + 1], rates[b, c][None], 3.0, 1.0
            )
            ref = information_gain_reference(
                poses.pos_enu_m[0], st.estimates_m[b], st.covariances_m2[b], 0.12
            )
            # gains of 60 nats here: the cofactor expansion of the Gram determinant missed by 1.7e-7
            # relative; the Cholesky pivots agree with eq. (29) (and with 40-digit arithmetic) to 2e-12
            assert gain[b, c] == pytest.approx(ref, rel=1e-10, abs=1e-10)

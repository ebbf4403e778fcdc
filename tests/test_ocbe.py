"""OCBE transition matrix: block structure, symplectic-like identities, and Q equal to the exact process noise."""

import numpy as np
import pytest

from cislunar import covariance, ocbe, orbits
from cislunar.dynamics import EARTH_MOON as em
from cislunar.propagation import propagate_stm

Q_WEIGHT = 3.5e-6  # LU^2/TU^3 (1e-11 km^2/s^3)


@pytest.fixture(scope="module")
def two_hours_near_perilune():
    nrho = orbits.nrho_9_2(em)
    dt = float(em.days_to_tu(2.0 / 24.0))
    t0 = nrho.period / 2 - dt  # the two hours before perilune: the hardest stretch
    x_start = propagate_stm(em, nrho.x0, [0.0, t0]).x[-1]
    grid = np.linspace(0.0, dt, 5)
    return x_start, grid, ocbe.ocbe_transition(em, x_start, grid, Q_WEIGHT)


def test_state_block_is_the_ordinary_stm_and_costate_blocks_have_the_adjoint_structure(two_hours_near_perilune):
    x0, grid, tr = two_hours_near_perilune
    ref = propagate_stm(em, x0, grid)
    assert np.max(np.abs(tr.x - ref.x)) < 1e-13
    assert np.max(np.abs(tr.phi_xx - ref.stm)) < 1e-10 * np.max(np.abs(ref.stm))
    assert np.max(np.abs(tr.phi_px)) == 0.0
    for k in range(1, grid.size):
        inv_t = np.linalg.inv(tr.phi_xx[k]).T
        assert np.max(np.abs(tr.phi_pp[k] - inv_t)) < 1e-9 * np.max(np.abs(inv_t))
        M = tr.phi_xp[k] @ tr.phi_xx[k].T
        assert np.max(np.abs(M - M.T)) < 1e-9 * np.max(np.abs(M))


def test_ocbe_process_noise_equals_exact_white_noise_discretisation(two_hours_near_perilune):
    x0, grid, tr = two_hours_near_perilune
    Q_ocbe = ocbe.ocbe_process_noise(tr.phi[-1])
    Q_exact = covariance.process_noise_lyapunov(em, x0, grid[-1], Q_WEIGHT)
    assert np.max(np.abs(Q_ocbe - Q_exact)) < 1e-8 * np.max(np.abs(Q_exact))
    assert np.linalg.eigvalsh(Q_ocbe).min() > 0  # controllable through accelerations: full rank
    with pytest.raises(ValueError, match="phi"):
        ocbe.ocbe_process_noise(np.random.default_rng(0).standard_normal((12, 12)))


def test_estimated_control_and_bad_input(two_hours_near_perilune):
    _, _, tr = two_hours_near_perilune
    p = np.r_[np.zeros(3), 1.0, -2.0, 0.5]
    u = ocbe.estimated_control(Q_WEIGHT, tr.phi_pp, p)
    assert u.shape == (tr.t.size, 3)
    assert np.allclose(u[0], -Q_WEIGHT * p[3:])
    with pytest.raises(ValueError, match="control_weight"):
        ocbe.ocbe_transition(em, tr.x[0], 0.1, -1.0)
    with pytest.raises(ValueError, match="p"):
        ocbe.estimated_control(Q_WEIGHT, tr.phi_pp, np.zeros(5))

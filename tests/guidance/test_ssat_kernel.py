"""The fast measurement loop of ``ssat.ssat_covariance`` is bit-identical to the numpy-wrapper form it replaced.

``_reference_loop`` is the loop as it was written with ``np.linalg.qr(..., mode="r")``, ``np.linalg.solve`` and one
``einsum`` per epoch; ``ssat._sri_range_variance`` calls the same LAPACK gufuncs without the wrappers and forms
every :math:`\\Phi_k^Tm_k` at once.  Equality is exact (``np.array_equal``), so every number of notebooks 07 and 08
that comes from the covariance analysis is unchanged.
"""

from __future__ import annotations

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.propagation import propagate
from cislunar.guidance import ssat

HR = 3600.0 / em.time_unit_s


def _reference_loop(R, A, stm_a, stm_t, M):
    n, N = A.shape[:2]
    J = np.empty((n, N))
    for k in range(N):
        R = np.linalg.qr(np.concatenate([R, A[:, k]], axis=-2), mode="r")[..., :12, :]
        g = np.concatenate([np.einsum("nji,nj->ni", stm_a[:, k], M[:, k, :6]),
                            np.einsum("nji,nj->ni", stm_t[:, k], M[:, k, 6:])], axis=-1)
        w = np.linalg.solve(np.swapaxes(R, -1, -2), g[..., None])[..., 0]
        J[:, k] = np.sum(w * w, axis=-1)
    return J, R


@pytest.fixture(scope="module")
def case():
    """Target at the 9:2 NRHO apolune, agent 0.6 h behind; 6 burn directions at t0 and a 30-h grid."""
    o = nrho_9_2(em)
    xa0 = propagate(em, o.x0, np.array([0.0, -0.6 * HR])).x[-1]
    t = np.arange(31) * HR
    target = ssat.propagate_with_impulses(em, o.x0, t)
    D = ssat.fibonacci_sphere(6)
    agent = ssat.propagate_with_impulses(em, np.broadcast_to(xa0, (6, 6)), t, [(t[0], 1e-3 / em.velocity_unit_km_s * D)])
    return agent, target, ssat.initial_covariance(em)


def _inputs(agent, target, P0):
    n, N = agent.x.shape[0], agent.t.size
    xt = np.broadcast_to(target.x, (n, N, 6))
    st = np.broadcast_to(target.stm, (n, N, 6, 6))
    H, _, _ = ssat._measurement_rows(em, agent.x, xt, ssat.AMOS_SIGMA_MIN_RAD, ssat.AMOS_RESOLUTION_KM)
    A = np.concatenate([H[..., :6] @ agent.stm, H[..., 6:] @ st], axis=-1)
    R = np.broadcast_to(np.linalg.inv(np.linalg.cholesky(P0)), (n, 12, 12)).copy()
    M = ssat.range_projection(np.concatenate([agent.x, xt], axis=-1), "inertial")
    return R, A, agent.stm, st, M


@pytest.mark.parametrize("correlated", [False, True], ids=["diagonal P0", "correlated P0"])
@pytest.mark.parametrize("batch", [slice(None), slice(2, 3)], ids=["six trajectories", "one trajectory"])
def test_kernel_is_bit_identical_to_the_wrapper_form(case, batch, correlated):
    agent, target, P0 = case
    if correlated:  # a full P0: the initial square root is then not upper triangular (a full first QR)
        C = 0.3 * np.random.default_rng(4).standard_normal((12, 12))
        s = np.sqrt(np.diag(P0))
        P0 = (s[:, None] * s) * (np.eye(12) + C @ C.T) / (1.0 + np.max(np.sum(C * C, axis=1)))
        P0 = 0.5 * (P0 + P0.T)
    sub = ssat.ImpulsiveTrajectory(agent.t, agent.x[batch], agent.stm[batch])
    args = _inputs(sub, target, P0)
    J_ref, R_ref = _reference_loop(*args)
    J, R = ssat._sri_range_variance(*args)
    assert np.array_equal(J, J_ref) and np.array_equal(R, R_ref)
    # and through the public function (final covariance from the same R)
    cov = ssat.ssat_covariance(em, sub, target, P0)
    assert np.array_equal(cov.J_rho, J_ref)


def test_kernel_raises_like_numpy_on_a_singular_information_matrix(case):
    agent, target, P0 = case
    R, A, sa, st, M = _inputs(agent, target, P0)
    R, A = np.zeros_like(R), np.zeros_like(A)  # no information at all: R stays singular
    with pytest.raises(np.linalg.LinAlgError):
        _reference_loop(R, A, sa, st, M)
    with pytest.raises(np.linalg.LinAlgError):
        ssat._sri_range_variance(R, A, sa, st, M)

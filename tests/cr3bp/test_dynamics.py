"""CR3BP vector field, Jacobian, Jacobi constant and libration points."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from cislunar.cr3bp.dynamics import CR3BP, EARTH_MOON, SYNODIC_MONTH_DAYS

em = EARTH_MOON

# states away from the primaries
finite = st.floats(-1.5, 1.5, allow_nan=False)
states = arrays(float, 6, elements=finite).filter(
    lambda s: min(np.linalg.norm(s[:3] - em.primary_position), np.linalg.norm(s[:3] - em.secondary_position)) > 0.05
)


def test_constants_and_units():
    assert em.mu == 0.012150585609624
    assert abs(em.time_unit_days - 375190.25852 / 86400) < 1e-15
    assert abs(em.velocity_unit_km_s - 384400 / 375190.25852) < 1e-15
    # the time unit follows from Kepler's third law with G(M_E + M_M) = 403503.2355 km^3/s^2 (DE-like value)
    gm = 384400.0**3 / em.time_unit_s**2
    assert abs(gm - 403503.2355) / gm < 1e-4
    assert abs(em.synodic_month_tu() - SYNODIC_MONTH_DAYS / em.time_unit_days) < 1e-15
    s = np.array([0.9, 0.1, -0.2, 0.01, 0.3, -0.02])
    assert np.allclose(em.state_from_km(em.state_to_km(s)), s, rtol=0, atol=1e-15)


@given(states)
def test_jacobian_matches_finite_differences(s):
    A = em.jacobian(s)
    h = 1e-6
    fd = np.empty((6, 6))
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        fd[:, j] = (em.eom(s + e) - em.eom(s - e)) / (2 * h)
    assert np.max(np.abs(A - fd)) <= 1e-6 * max(1.0, np.max(np.abs(A)))


@given(states)
def test_jacobi_constant_gradient_is_orthogonal_to_the_flow(s):
    # dC/dt = grad C . f = 0 identically for the CR3BP
    h = 1e-6
    grad = np.array([(em.jacobi(s + h * e) - em.jacobi(s - h * e)) / (2 * h) for e in np.eye(6)])
    f = em.eom(s)
    assert abs(grad @ f) <= 1e-6 * (1 + np.linalg.norm(grad) * np.linalg.norm(f))


def test_vectorised_forms_agree_with_single_state():
    rng = np.random.default_rng(1)
    S = np.array([0.8, 0, 0, 0, 0.5, 0]) + 0.05 * rng.standard_normal((5, 3, 6))
    F = em.eom(S)
    A = em.jacobian(S)
    C = em.jacobi(S)
    assert F.shape == (5, 3, 6) and A.shape == (5, 3, 6, 6) and C.shape == (5, 3)
    for i, j in [(0, 0), (4, 2)]:
        assert np.array_equal(F[i, j], em.eom(S[i, j]))
        assert np.array_equal(A[i, j], em.jacobian(S[i, j]))
        assert C[i, j] == em.jacobi(S[i, j])


def test_libration_points():
    L = em.libration_points()
    for p in L:
        assert np.max(np.abs(em.eom(np.r_[p, 0, 0, 0]))) < 1e-13
    # published Earth-Moon values to six digits (e.g. Szebehely-style tables): 0.836915, 1.155682, -1.005063
    assert np.allclose(L[:3, 0], [0.836915, 1.155682, -1.005063], rtol=0, atol=6e-7)
    # independent route: Szebehely's quintic for gamma = distance of L1/L2 from the Moon, solved by numpy.roots
    mu = em.mu
    for k, sign in ((0, -1), (1, +1)):
        # gamma^5 -+ (3-mu) gamma^4 + (3-2mu) gamma^3 - mu gamma^2 +- 2 mu gamma - mu = 0 (upper sign L1)
        coeffs = [1, sign * (3 - mu), 3 - 2 * mu, -mu, -sign * 2 * mu, -mu]
        roots = np.roots(coeffs)
        gamma = [r.real for r in roots if abs(r.imag) < 1e-12 and 0 < r.real < 1]
        assert len(gamma) == 1
        assert abs(L[k, 0] - (1 - mu + sign * gamma[0])) < 1e-12
    assert np.allclose(L[3], [0.5 - em.mu, np.sqrt(3) / 2, 0])
    # Jacobi constants ordered C1 > C2 > C3 > C4 = C5 = 3 - mu (1 - mu)
    C = em.jacobi(np.c_[L, np.zeros((5, 3))])
    assert C[0] > C[1] > C[2] > C[3]
    assert abs(C[3] - (3 - em.mu * (1 - em.mu))) < 1e-13


@pytest.mark.parametrize(
    "bad, word",
    [(np.zeros(5), "state"), (np.array([np.nan, 0, 0, 0, 0, 0]), "NaN"), (np.zeros((2, 7)), "state")],
)
def test_bad_state_raises(bad, word):
    with pytest.raises(ValueError, match=word):
        em.eom(bad)


@pytest.mark.parametrize("mu", [0.0, -0.1, 0.6, float("nan")])
def test_bad_mass_parameter(mu):
    with pytest.raises(ValueError, match="mu"):
        CR3BP(mu=mu, length_unit_km=1.0, time_unit_s=1.0)


def test_bad_units():
    with pytest.raises(ValueError, match="length_unit_km"):
        CR3BP(mu=0.01, length_unit_km=-1.0, time_unit_s=1.0)

"""Sundman nodes, Eq. 41 bounds and the first-order-hold discretisation against nonlinear propagation."""

import numpy as np
import pytest

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import propagate, propagate_stm
from cislunar.guidance import discretization as D


@pytest.fixture(scope="module")
def nrho():
    return orbits.nrho_9_2(em)


def test_sigma_zero_gives_uniform_nodes_and_positive_sigma_crowds_perilune(nrho):
    t0, tau0 = D.sundman_nodes(em, nrho.x0, nrho.period, 21, 0.0)
    assert np.allclose(t0, np.linspace(0, nrho.period, 21), atol=1e-12)
    assert np.allclose(tau0, t0, atol=1e-12)  # dt = d tau when sigma = 0
    t1, tau1 = D.sundman_nodes(em, nrho.x0, nrho.period, 21, 1.5)
    dt = np.diff(t1)
    mid = np.argmin(dt)  # smallest interval sits at perilune (half period from apolune)
    assert abs(0.5 * (t1[mid] + t1[mid + 1]) - nrho.period / 2) < 0.05 * nrho.period
    assert dt.max() / dt.min() > 10
    # tau really is the integral of r_m^-sigma: check one node by quadrature on a fine grid
    tt = np.linspace(0, t1[5], 20001)
    r = np.linalg.norm(propagate(em, nrho.x0, tt).x[:, :3] - em.secondary_position, axis=1)
    assert abs(np.trapezoid(r**-1.5, tt) - tau1[5]) < 1e-6 * tau1[5]


def test_eq41_minimum_norm_bounds():
    rng = np.random.default_rng(0)
    t = np.cumsum(np.r_[0.0, rng.uniform(0.1, 1.0, 9)])
    u = D.max_control_per_node(t, 2.0)
    dt = np.diff(t)
    assert np.allclose((u[:-1] + u[1:]) / (2 * dt), 2.0, rtol=0, atol=1e-12)  # Eq. 40 on every interval
    # minimum norm: orthogonal to the null space of the Eq. 41 matrix (alternating +-1 pattern)
    null = (-1.0) ** np.arange(t.size)
    assert abs(u @ null) < 1e-10 * np.linalg.norm(u)
    with pytest.raises(ValueError, match="t_nodes"):
        D.max_control_per_node([0.0, 1.0, 0.5], 1.0)


def test_foh_model_matches_nonlinear_propagation_and_stm(nrho):
    t = np.linspace(0.0, 0.6, 7)
    x_ref = propagate(em, nrho.x0, t).x
    u_ref = 1e-3 * np.sin(np.arange(7))[:, None] * np.array([1.0, -0.5, 0.3])
    model = D.foh_discretize(em, t, x_ref, u_ref)
    # the affine model is exact at the reference, and A_k is the ordinary STM of a ballistic arc when u = 0
    assert np.max(np.abs(model.predict(x_ref, u_ref) - model.x_next)) < 1e-13
    ballistic = D.foh_discretize(em, t, x_ref, np.zeros((7, 3)))
    stm = propagate_stm(em, x_ref[2], [t[2], t[3]]).stm[-1]
    assert np.max(np.abs(ballistic.A[2] - stm)) < 1e-11 * np.max(np.abs(stm))
    assert np.max(np.abs(ballistic.defects)) < 1e-12  # reference is a ballistic trajectory
    # B-, B+ and E against central differences of the nonlinear FOH propagation
    h = 1e-7
    k = 3
    for which, col in (("Bm", 0), ("Bp", 1)):
        for j in range(3):
            du = np.zeros((7, 3))
            du[k + col, j] = h
            xp = D.foh_discretize(em, t, x_ref, u_ref + du).x_next[k]
            xm = D.foh_discretize(em, t, x_ref, u_ref - du).x_next[k]
            fd = (xp - xm) / (2 * h)
            B = getattr(model, which)[k][:, j]
            assert np.max(np.abs(B - fd)) < 1e-6 * np.max(np.abs(fd))
    # virtual control E_k = integral of Phi(t_k+1, tau) (E(t) = I): check its velocity rows on a tiny interval
    tiny = D.foh_discretize(em, np.array([0.0, 1e-4]), x_ref[:2] * 0 + x_ref[0], np.zeros((2, 3)))
    assert np.allclose(tiny.E[0], 1e-4 * np.eye(6), atol=1e-7)


def test_linearisation_error_is_second_order(nrho):
    t = np.linspace(0.0, 1.0, 11)
    x_ref = propagate(em, nrho.x0, t).x
    u_ref = np.zeros((11, 3))
    model = D.foh_discretize(em, t, x_ref, u_ref)
    errs = []
    for scale in (1e-4, 1e-5):
        du = scale * np.ones((11, 3))
        truth = D.propagate_foh(em, x_ref[0], t, du)
        lin = model.predict(truth, du)  # one-step predictions from the true node states
        errs.append(np.max(np.abs(lin - truth[1:])))
    assert 50 < errs[0] / errs[1] < 200  # ~100x for a 10x smaller perturbation


def _falling_at_moon():
    """A state 0.02 LU (7700 km) from the Moon's centre, at rest in the rotating frame: it falls onto the Moon."""
    return np.array([1.0 - em.mu - 0.02, 0.0, 0.0, 0.0, 0.0, 0.0])


def test_impact_with_the_moon_is_detected_not_integrated_through():
    x0 = _falling_at_moon()
    t = np.linspace(0.0, 0.2, 5)
    with pytest.raises(RuntimeError, match="Moon"):
        D.propagate_foh(em, x0, t, np.zeros((5, 3)))
    with pytest.raises(RuntimeError, match="Moon"):
        D.sundman_nodes(em, x0, 0.2, 5, 1.0)
    with pytest.raises(RuntimeError, match="Moon"):
        D.foh_discretize(em, t[:2], np.array([x0, x0]), np.zeros((2, 3)))
    # a node state inside a primary is refused before integrating
    inside = np.array([1.0 - em.mu + 0.5 * em.secondary_radius, 0, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="x_nodes"):
        D.foh_discretize(em, t[:2], np.array([inside, x0]), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="x0"):
        D.propagate_foh(em, inside, t, np.zeros((5, 3)))
    # the same fall stopped short of the surface is fine and agrees with the plain propagator
    t_short = np.linspace(0.0, 0.01, 3)
    assert np.allclose(D.propagate_foh(em, x0, t_short, np.zeros((3, 3)))[-1],
                       propagate(em, x0, t_short).x[-1], atol=1e-12)

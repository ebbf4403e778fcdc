"""No junk from the mission modules (issue 11): tori, transfers and SSAT analyses refuse what is not physical.

The malformed-argument sweep of ``tests/test_reliability.py`` (specs in ``reliability_specs_missions.py``) covers
wrong types, shapes and ranges.  These tests cover what a per-argument sweep cannot: a torus ring inside the Moon, a
degenerate (zero-size) circle, a transfer flown through the Moon, an angular-noise model with no noise, arguments
that only clash with each other, and configuration errors that must not look like filter divergence.
"""

from __future__ import annotations

import functools
import pickle
from dataclasses import replace

import numpy as np
import pytest

from cislunar.cr3bp import torus as tm
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.propagation import propagate
from cislunar.guidance import ssat
from cislunar.papers.greaves_scheeres_2023 import station_keeping as sk

HR = 3600.0 / em.time_unit_s


@functools.lru_cache(maxsize=None)
def _orbit():
    return nrho_9_2(em)


@functools.lru_cache(maxsize=None)
def _torus():
    return tm.torus_from_orbit(_orbit(), 5, 10.0)


@functools.lru_cache(maxsize=None)
def _pair():
    xt0 = _orbit().x0.copy()
    return propagate(em, xt0, np.array([0.0, -0.6 * HR])).x[-1], xt0


# ------------------------------------------------------------------------------------------------- tori
def test_a_ring_inside_the_moon_is_not_a_torus():
    torus = _torus()
    circle = torus.circle.copy()
    circle[2, :3] = em.secondary_position + np.array([0.5, 0.0, 0.0]) * em.secondary_radius
    with pytest.raises(ValueError, match="circle point 2 lies inside the Moon"):
        replace(torus, circle=circle)


def test_a_degenerate_circle_is_refused_everywhere():
    torus, orbit = _torus(), _orbit()
    with pytest.raises(ValueError, match="circle is degenerate"):
        replace(torus, circle=np.tile(orbit.x0, (5, 1)))
    with pytest.raises(ValueError, match="size_km"):
        tm.torus_seed(orbit, 5, 1e-9)
    with pytest.raises(ValueError, match=r"fix\['size_km'\]"):
        tm.solve_torus(torus, fix={"size_km": 1e-9})
    with pytest.raises(ValueError, match=r"fix\['size'\]"):
        tm.solve_torus(torus, fix={"size": 1e-12})


def test_the_corrector_does_not_return_a_degenerate_circle(monkeypatch):
    """A solve whose converged ring is below the size floor raises instead of returning the base orbit."""
    torus = _torus()
    monkeypatch.setattr(tm, "_MIN_SIZE_LU", 10.0 * torus.size)  # the 10-km ring now counts as degenerate
    with pytest.raises(tm.TorusConvergenceError, match="degenerate circle") as info:
        tm.solve_torus(torus, fix={"jacobi": torus.jacobi}, check_midpoints=False)
    err = info.value
    assert err.reason == "degenerate" and err.residuals and err.residuals[-1] < 1e-11
    back = pickle.loads(pickle.dumps(err))
    assert back.reason == "degenerate" and back.residuals == err.residuals


def test_free_period_continuation_needs_one_held_constraint():
    with pytest.raises(ValueError, match="hold"):
        tm.continue_tori(_torus(), [11.0], free_period=True, progress=False)
    with pytest.raises(ValueError, match="hold"):
        tm.continue_tori(_torus(), [11.0], hold={"jacobi": _torus().jacobi}, progress=False)


def test_integer_arguments_are_not_truncated():
    torus = _torus()
    for call, name in ((lambda: torus.ring(0.0, 2.9), "n_theta"),
                       (lambda: tm.mean_range(torus, periods=1.5), "periods"),
                       (lambda: tm.mean_range(torus, n_t=20.5), "n_t"),
                       (lambda: torus.closest_approach(n_theta=True), "n_theta")):
        with pytest.raises((TypeError, ValueError), match=name):
            call()


# ------------------------------------------------------------------------------------------------- transfers
def test_a_transfer_through_the_moon_is_a_convergence_failure():
    """A straight shot across the Moon: the first Newton iterate hits the surface and the transfer is refused."""
    mu = em.mu
    x0 = np.array([1 - mu + 0.02, 0.0, 0.0, 0.0, 0.0, 0.0])
    with pytest.raises(sk.TransferConvergenceError, match="impact on the Moon") as info:
        sk.position_transfer(em, x0, 0.0, 0.1, np.array([1 - mu - 0.02, 0.0, 0.0]))
    err = info.value
    assert err.reason == "impact" and err.failed == [0]
    back = pickle.loads(pickle.dumps(err))
    assert back.reason == "impact" and back.failed == [0] and str(back) == str(err)


def test_transfer_batches_must_match():
    x0 = np.tile(_orbit().x0, (3, 1))
    with pytest.raises(ValueError, match="x0 and r_target"):
        sk.position_transfer(em, x0, 0.0, 0.1, np.zeros((2, 3)) + _orbit().x0[:3])


# ------------------------------------------------------------------------------------------------- SSAT
def test_an_angular_noise_model_without_noise_is_refused():
    xa0, xt0 = _pair()
    t = np.array([0.0, 1.0, 2.0]) * HR
    ag, tg = ssat.propagate_with_impulses(em, xa0, t), ssat.propagate_with_impulses(em, xt0, t)
    P0 = ssat.initial_covariance(em)
    for fn in (ssat.ssat_covariance, ssat.ssat_covariance_ekf):
        with pytest.raises(ValueError, match="sigma_min_rad and resolution_km are both zero"):
            fn(em, ag, tg, P0, sigma_min_rad=0.0, resolution_km=0.0)
    fn(em, ag, tg, P0, sigma_min_rad=0.0, resolution_km=4e-3)  # one of them is enough


def test_coincident_agent_and_target_are_refused():
    t = np.array([0.0, 1.0, 2.0]) * HR
    tg = ssat.propagate_with_impulses(em, _pair()[1], t)
    for fn in (ssat.ssat_covariance, ssat.ssat_covariance_ekf):
        with pytest.raises(ValueError, match=r"agent and target coincide at t\[0\]"):
            fn(em, tg, tg, ssat.initial_covariance(em))
    x0 = np.tile(_orbit().x0, (3, 1))
    with pytest.raises(ValueError, match="x0 and x_target"):
        sk.two_burn_transfer(em, x0, 0.0, 0.1, np.tile(_orbit().x0, (2, 1)))


def test_minimize_range_sigma_refines_with_the_callers_noise_model():
    """The refined optimum's J is that of its direction under the caller's Eq. 20 noise (not the default's)."""
    xa0, xt0 = _pair()
    t = np.array([0.0, 1.0, 2.0, 3.0]) * HR
    v = 1e-3 / em.velocity_unit_km_s  # 1 m/s
    P0 = ssat.initial_covariance(em)
    noise = dict(sigma_min_rad=1e-4, resolution_km=4e-2)  # ten times the AMOS values
    d, J = ssat.minimize_range_sigma(em, xa0, xt0, t, v, P0, n_grid=40, refine=True, **noise)
    check = ssat.range_sigma_over_directions(em, xa0, xt0, t, v, d[None], P0, **noise).J_rho[0, -1]
    assert np.isclose(J, check, rtol=1e-10)
    grid = ssat.range_sigma_over_directions(em, xa0, xt0, t, v, ssat.fibonacci_sphere(40), P0, **noise)
    assert J <= grid.J_rho[:, -1].min() * (1 + 1e-12)


def test_impulsive_trajectory_fields_must_agree():
    xa0, _ = _pair()
    t = np.array([0.0, 1.0, 2.0]) * HR
    tr = ssat.propagate_with_impulses(em, xa0, t)
    with pytest.raises(ValueError, match="x must have shape"):
        ssat.ImpulsiveTrajectory(t[:2], tr.x, tr.stm)
    with pytest.raises(ValueError, match="stm must have shape"):
        ssat.ImpulsiveTrajectory(t, tr.x, tr.stm[:, :2])
    with pytest.raises(TypeError, match="impulses"):
        ssat.propagate_with_impulses(em, xa0, t, "ab")


def test_shape_clashes_name_the_first_argument():
    dv1 = np.ones((2, 3, 3))
    with pytest.raises(ValueError, match="u_y.*dv1"):
        sk.informed_choice(dv1, np.ones((3, 3)), np.ones((2, 3)))
    with pytest.raises(ValueError, match="cost.*dv1"):
        sk.informed_choice(dv1, np.ones((2, 3)), np.ones((2, 4)))
    with pytest.raises(ValueError, match="x"):
        ssat.to_relative(np.ones(5))


# ------------------------------------------------------------------------------------------------- filter trials
@functools.lru_cache(maxsize=None)
def _scenario():
    surf = sk.station_keeping_surface(em, _torus(), np.array([0.0, 2.0]), np.array([-1.0]) * HR, -3.0 * HR, 0.0,
                                      progress=False)
    tgt0 = propagate(em, _orbit().x0, np.array([0.0, surf.t[0]])).x[-1]
    return sk.filter_scenario(surf, 0, 1, tgt0, em)


def test_configuration_errors_are_exceptions_not_diverged_trials():
    sc = _scenario()
    with pytest.raises(TypeError, match="rng"):
        sk.filter_trial(None, sc)
    with pytest.raises(ValueError, match="n_iter"):
        sk.filter_trial(np.random.default_rng(0), sc, n_iter=0)
    with pytest.raises(TypeError, match=r"scenarios\[1\]"):
        sk.random_choice_trial(np.random.default_rng(0), [sc, "sc"])
    with pytest.raises(ValueError, match=r"burns\[1\] time"):
        replace(sc, burns=(sc.burns[0], (sc.t[-1] + 1.0, np.zeros(3))))
    with pytest.raises(ValueError, match="P0"):
        replace(sc, P0=-sc.P0)
    res = sk.filter_trial(np.random.default_rng(0), sc, n_iter=2)  # the valid configuration runs
    assert res.failure == "" and np.all(np.isfinite(res.nees))

"""Periodic orbits: closure, the 9:2 and stable NRHOs, DROs of Wolf & Jones, monodromy structure, failures."""

import numpy as np
import pytest

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.wolf_jones.reference import load_wolf_jones_table, verify_table_row


@pytest.fixture(scope="module")
def nrho():
    return orbits.nrho_9_2(em)


@pytest.fixture(scope="module")
def stable():
    return orbits.stable_nrho(em)


@pytest.fixture(scope="module")
def halo_family():
    return orbits.l2_southern_halo_family(em, step=0.03, n_l2ward=60)


@pytest.fixture(scope="module")
def dros():
    return orbits.dro_family(em, np.linspace(0.95, 0.70, 26))


def test_nrho_9_2_period_and_geometry(nrho):
    target = 2.0 / 9.0 * em.synodic_month_tu()
    assert abs(nrho.period - target) / target < 1e-8
    assert nrho.closure < 1e-10
    assert nrho.x0[2] < 0  # southern: apolune below the Earth-Moon plane
    assert 3100 < nrho.perilune_radius_km < 3400  # reference notes: about 3200-3300 km
    assert 70000 < nrho.apolune_radius_km < 72000


def test_stable_nrho_has_unit_stability_index(stable, nrho):
    assert abs(stable.stability_index - 1.0) < 1e-3
    assert stable.closure < 1e-10
    assert stable.perilune_radius_km < nrho.perilune_radius_km
    assert nrho.stability_index > 1.2  # the 9:2 NRHO itself is mildly unstable


def test_every_family_member_closes(halo_family, dros):
    for orb in halo_family + dros:
        assert orb.closure < 1e-10, (orb.label, orb.x0, orb.closure)
        assert orb.residuals[-1] < 1e-12


@pytest.mark.parametrize("which", ["halo", "dro"])
def test_monodromy_eigenvalues_come_in_reciprocal_pairs(which, halo_family, dros):
    fam = halo_family if which == "halo" else dros
    for orb in fam[:: max(1, len(fam) // 6)]:
        lam = orb.eigenvalues
        # det M = 1 and the spectrum is closed under lambda -> 1/lambda (and conjugation)
        assert abs(np.prod(lam) - 1) < 1e-6 * np.max(np.abs(lam)) ** 2
        for value in lam:
            assert np.min(np.abs(lam - 1.0 / value)) < 1e-6 * max(1.0, abs(value), abs(1 / value))
        # two eigenvalues at 1 (the periodic orbit and the family direction)
        assert np.sum(np.abs(lam - 1) < 1e-3) >= 2
        # the Broucke indices agree with the eigenvalues
        nu = orb.broucke_indices
        idx_from_eig = 0.5 * (np.max(np.abs(lam)) + 1 / np.max(np.abs(lam)))
        assert abs(max(1.0, np.max(np.abs(nu.real))) - idx_from_eig) < 1e-6 * idx_from_eig


def test_dros_are_stable_and_planar(dros):
    for orb in dros:
        assert orb.is_planar
        assert abs(orb.stability_index - 1) < 1e-6


def test_wolf_jones_table_rows():
    rows = load_wolf_jones_table()
    assert len(rows) == 8
    checks = [verify_table_row(em, r) for r in rows]
    by_label = {(c.table, c.label): c for c in checks}
    # the printed observer state (vy0 = 0.528996986) is not periodic; every other row closes to the printed digits
    assert not by_label[(2, "observer_t0")].periodic_as_printed
    assert by_label[(2, "observer_t0")].raw_closure > 0.1
    for c in checks:
        if c.label != "observer_t0":
            assert c.periodic_as_printed, c
            assert abs(c.corrected.x0[4] - c.vy0) < 1e-8
        assert c.corrected.closure < 1e-10
        assert 15.5 < c.corrected.period_days < 16.5


def test_closure_tolerance_rejects_a_wrong_mass_parameter():
    """CLOSURE_TOL passes the printed rows with our mass parameter and fails every one of them with mu off by 1e-9
    (closures 2-2.5e-7), which a loose tolerance such as 1e-6 would pass up to mu off by 4e-9."""
    from dataclasses import replace

    from cislunar.papers.wolf_jones.reference import CLOSURE_TOL

    rows = [r for r in load_wolf_jones_table() if r.label != "observer_t0"]
    for row in rows:
        assert verify_table_row(em, row).raw_closure < CLOSURE_TOL / 3
        off = verify_table_row(replace(em, mu=em.mu + 1e-9), row)
        assert not off.periodic_as_printed and CLOSURE_TOL < off.raw_closure < 1e-6


def test_shooting_failure_raises_with_residual_history():
    with pytest.raises(orbits.ConvergenceError, match="residual history") as info:
        orbits.correct_symmetric(em, [1.1, 0, -0.3, 0, 0.9, 0], 1.0, fix="x0", max_iter=3)
    assert len(info.value.residuals) == 3


@pytest.mark.parametrize(
    "kwargs, word",
    [
        (dict(x0_guess=np.zeros(4)), "x0_guess"),
        (dict(x0_guess=[0.8, 0, 0, 0, 0.5, 0], half_period=-1.0), "half_period"),
        (dict(x0_guess=[0.8, 0, 0, 0, 0.5, 0], half_period=1.0, fix="z0"), "fix"),
        (dict(x0_guess=[0.8, 0, 0, 0, 0.5, 0], half_period=1.0, tol=0.5), "tol"),
    ],
)
def test_bad_arguments(kwargs, word):
    with pytest.raises(ValueError, match=word):
        orbits.correct_symmetric(em, **kwargs)


def test_stability_index_conventions():
    # a hyperbolic pair (3, 1/3) and an elliptic pair (e^{+-i}) plus the trivial pair
    D = np.diag([3.0, 1 / 3.0, 1.0, 1.0, 1.0, 1.0])
    D[4:, 4:] = [[np.cos(1.0), -np.sin(1.0)], [np.sin(1.0), np.cos(1.0)]]
    Q = np.linalg.qr(np.random.default_rng(0).standard_normal((6, 6)))[0]
    M = Q @ D @ Q.T
    assert abs(orbits.stability_index(M) - (3 + 1 / 3) / 2) < 1e-12
    assert np.allclose(orbits.broucke_indices(M), [(3 + 1 / 3) / 2, np.cos(1.0)], atol=1e-12)
    with pytest.raises(ValueError, match="monodromy"):
        orbits.stability_index(np.eye(5))


def test_natural_and_pseudo_arclength_continuation_trace_the_same_family(nrho):
    arc = orbits.continue_family(em, nrho, 6, -0.01, parameter="half_period")
    target = arc[-1]
    # natural-parameter continuation in two steps of the half period lands on the same orbit
    dtau = (target.period - nrho.period) / 2
    nat = orbits.continue_family(em, nrho, 2, dtau / 2, method="natural", parameter="half_period")
    assert abs(nat[-1].period - target.period) < 1e-12
    assert np.max(np.abs(nat[-1].x0 - target.x0)) < 1e-9
    for o in nat + arc:
        assert o.closure < 1e-10
    # the pseudo-arclength steps have the requested length in the free-variable space
    X = [np.array([o.x0[0], o.x0[2], o.x0[4], o.period / 2]) for o in arc]
    assert np.allclose([np.linalg.norm(b - a) for a, b in zip(X, X[1:])], 0.01, rtol=0.02)


def test_integrators_are_compiled_once_per_process():
    from cislunar.cr3bp import propagation
    propagation.propagate_stm(em, [0.8, 0, 0, 0, 0.5, 0], 0.1)
    before = propagation._template.cache_info()
    first = propagation._integrator(1, 1, propagation.DEFAULT_TOL)
    propagation.propagate_stm(em, [0.8, 0, 0, 0, 0.5, 0], 0.2)
    assert propagation._template.cache_info().misses == before.misses
    assert propagation._integrator(1, 1, propagation.DEFAULT_TOL) is first  # this thread's working copy is reused


def test_stable_nrho_outer_band_member_is_stable_and_far_from_the_moon(nrho):
    outer = orbits.stable_nrho_outer(em)
    # linearly stable: every Broucke index inside [-1, 1] (all multipliers on the unit circle)
    assert np.max(np.abs(outer.broucke_indices.real)) < 1.0
    assert abs(outer.stability_index - 1.0) < 1e-6
    assert outer.closure < 1e-10
    # the outer band lies L2-ward of the 9:2 NRHO: larger perilune, longer period
    assert 13000.0 < outer.perilune_radius_km < 20000.0
    assert outer.period > nrho.period
    assert outer.label == "stable NRHO (outer band)"

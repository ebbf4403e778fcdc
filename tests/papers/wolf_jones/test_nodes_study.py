"""Notebook 04's studies: Sundman nodes, the second-order decay of the affine model's error, the Eq. 40 residual."""

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.wolf_jones import nodes_study as S


@pytest.fixture(scope="module")
def sweep():
    return S.node_sweep(em, S.reference_arcs(em), [0.0, 1.0], 12)


def test_nodes_dilate_with_sigma(sweep):
    assert list(sweep.arcs) == [S.DRO_ARC, S.NRHO_ARC]
    spread = sweep.spread
    for name in sweep.arcs:
        t = sweep.nodes[name, 0.0]
        assert spread[name, 0.0] == pytest.approx(1.0, abs=1e-6) and t[0] == 0.0
        assert t[-1] == pytest.approx(sweep.arcs[name][1])
    # the NRHO's distance to the Moon varies far more than the DRO's, and so does the spacing
    assert spread[S.NRHO_ARC, 1.0] > spread[S.DRO_ARC, 1.0] > 1.0
    r = S.moon_distance_km(em, *sweep.arcs[S.NRHO_ARC], n=300)
    assert r.max() / r.min() > 5


def test_linearisation_error_is_second_order(sweep):
    x0, t = sweep.arcs[S.DRO_ARC][0], sweep.nodes[S.DRO_ARC, 0.0]
    a = 0.01 * S.A_MAX_KM_S2 / em.acceleration_unit_km_s2  # small enough for the asymptotic regime
    e1 = S.linearisation_error(em, x0, t, 1, np.random.default_rng(3), a)
    e2 = S.linearisation_error(em, x0, t, 1, np.random.default_rng(3), 2 * a)
    assert e1 > 0 and e2 / e1 == pytest.approx(4.0, rel=0.05)
    assert S.linearisation_error(em, x0, t, 1, np.random.default_rng(3), 0.0) < 1e-6 * e1


def test_sweep_gains_and_seeds():
    lin = S.LinearisationSweep({(S.DRO_ARC, 0.0): 2.0, (S.DRO_ARC, 1.0): 1.0, (S.DRO_ARC, 2.0): 4.0},
                               {5: {0.0: 3.0, 1.0: 2.0, 2.0: 1.0}})
    assert lin.gain(S.DRO_ARC, 1.0) == 2.0 and lin.best_gain(S.DRO_ARC) == (2.0, 1.0)
    assert lin.dro_gains(1.0) == [2.0, 1.5]
    with pytest.raises(ValueError, match="sigma = 0"):
        S.linearisation_sweep(em, S.NodeSweep({}, (1.0,), 3, {}), 1, np.random.default_rng(0), [], 1.0)


def test_eq40_residual_of_minimum_norm_bounds():
    t = np.array([0.0, 0.1, 0.4, 0.5, 1.2])
    assert S.eq40_residual(t, 2.0) < 1e-12


def test_linearisation_sweep_is_the_same_through_an_executor(sweep):
    """The profiles are drawn before any cell runs: an executor gives the serial result, and each cell equals
    linearisation_error drawing from the same generator state."""
    from concurrent.futures import ThreadPoolExecutor

    a = S.A_MAX_KM_S2 / em.acceleration_unit_km_s2
    serial = S.linearisation_sweep(em, sweep, 1, np.random.default_rng(7), [11], a)
    with ThreadPoolExecutor(2) as pool:
        pooled = S.linearisation_sweep(em, sweep, 1, np.random.default_rng(7), [11], a, executor=pool)
    assert serial == pooled
    assert list(serial.errors) == list(sweep.nodes) and list(serial.extra[11]) == [0.0, 1.0]
    rng = np.random.default_rng(7)
    first = S.linearisation_error(em, sweep.arcs[S.DRO_ARC][0], sweep.nodes[S.DRO_ARC, 0.0], 1, rng, a)
    assert serial.errors[S.DRO_ARC, 0.0] == first
    # every extra seed restarts its generator for each sigma
    again = S.linearisation_error(em, sweep.arcs[S.DRO_ARC][0], sweep.nodes[S.DRO_ARC, 1.0], 1,
                                  np.random.default_rng(11), a)
    assert serial.extra[11][1.0] == again

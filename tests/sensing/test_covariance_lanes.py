"""Interval propagations of several objects (the SCvx Hessian's 12 perturbed observers): the heyoka batch lanes
sorted by step count (``covariance._lane_order``) give each object its own arcs, bit for bit those of the given-order
path (before 2026-11-26d), with STTs that are central differences of the STM."""

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON
from cislunar.cr3bp.propagation import propagate, stt_finite_difference
from cislunar.sensing import covariance as C

# Wolf & Jones Table 4 observer row (a near-periodic DRO, period about 16 days)
OBSERVER = np.array([7.80136159e-1, 0, 0, 0, 5.53104815e-1, 0])
DAY = float(EARTH_MOON.days_to_tu(1.0))
H = 1e-5  # the perturbation of the Hessian's central differences (order of SCvx's hessian_step)


@pytest.fixture(scope="module")
def perturbed():
    """Twelve perturbed observers (x +- h e_j, as in WindowInformation.hessian) on a 5-interval daily grid."""
    t = np.arange(6) * DAY
    X0 = np.concatenate([OBSERVER + H * np.eye(6), OBSERVER - H * np.eye(6)], axis=0)
    return t, X0, C.propagate_arcs(EARTH_MOON, X0, t, order=2)


def test_sorted_lanes_give_each_observer_its_own_arcs(perturbed):
    """Each of the 12 objects' interval STMs and STTs equals those of the object propagated alone (one object: the
    lanes in the given order) to round-off; a wrong lane order (an interval's or another observer's transition
    scattered to the wrong place) differs by far more (different intervals: O(1); observers: O(h))."""
    t, X0, arcs = perturbed
    assert arcs.F.shape == (12, 5, 6, 6) and arcs.stt.shape == (12, 5, 6, 6, 6)
    for j in range(12):
        alone = C.propagate_arcs(EARTH_MOON, X0[j], t, order=2)
        np.testing.assert_allclose(arcs.x[j], alone.x[0], rtol=0, atol=1e-13)
        np.testing.assert_allclose(arcs.F[j], alone.F[0], rtol=0, atol=1e-12 * np.max(np.abs(alone.F[0])))
        np.testing.assert_allclose(arcs.stt[j], alone.stt[0], rtol=0, atol=1e-12 * np.max(np.abs(alone.stt[0])))
    # the observers differ by h: a lane swapped between two observers would move F by about h |dF/dx| >> 1e-12
    assert np.max(np.abs(arcs.F[0] - arcs.F[6])) > 1e-9 * np.max(np.abs(arcs.F[0]))


def test_sorted_lanes_equal_the_given_order_bit_for_bit(perturbed):
    """``_interval_transitions`` with sorted lanes against the given (observer-major) order on the same interval
    starts: the same transitions, STTs and process noise bit for bit (each heyoka lane has its own steps; the
    group's interval length stays the first interval's in the given order: the grid's lengths differ in their last
    bits, so taking the first sorted lane's length moves every result by about 1e-15)."""
    t, X0, arcs = perturbed
    starts = arcs.x[:, :-1].reshape(-1, 6)
    ends = arcs.x[:, 1:].reshape(-1, 6)
    dts = np.tile(np.diff(t), 12)
    assert len(set(np.diff(t).tolist())) > 1  # lengths grouped as equal that differ in the last bits
    F0, _, P0 = C._interval_transitions(EARTH_MOON, starts, dts, None, 12, 2, sort_lanes=False)
    F1, _, P1 = C._interval_transitions(EARTH_MOON, starts, dts, None, 12, 2, ends)
    assert not np.array_equal(C._lane_order(EARTH_MOON, starts, ends, dts), np.arange(60))  # really reordered
    assert np.array_equal(F1, F0) and np.array_equal(P1, P0)
    assert np.array_equal(F1.reshape(arcs.F.shape), arcs.F) and np.array_equal(P1.reshape(arcs.stt.shape), arcs.stt)
    # with a process-noise PSD the same (the quadrature grid and the noise follow their lanes)
    q = C.psd_to_nondimensional(1e-11, EARTH_MOON)
    F0, Q0, _ = C._interval_transitions(EARTH_MOON, starts, dts, q, 6, 1, sort_lanes=False)
    F1, Q1, _ = C._interval_transitions(EARTH_MOON, starts, dts, q, 6, 1, ends)
    assert np.array_equal(F1, F0) and np.array_equal(Q1, Q0)
    # one object (the gradient's arcs): its intervals sorted among themselves, the same bits
    one = C.propagate_arcs(EARTH_MOON, X0[3], t, order=2, q=q)
    F0, Q0, P0 = C._interval_transitions(EARTH_MOON, one.x[0, :-1], np.diff(t), q, 12, 2, sort_lanes=False)
    assert np.array_equal(one.F[0], F0) and np.array_equal(one.Q[0], Q0) and np.array_equal(one.stt[0], P0)


def test_lane_order_puts_the_perturbations_of_one_interval_in_one_batch(perturbed):
    """The order is a permutation, non-decreasing in the step-count estimate, and the 12 perturbed copies of each
    interval are consecutive (so every batch of 4 lanes holds one interval: lanes = perturbations)."""
    t, X0, arcs = perturbed
    starts = arcs.x[:, :-1].reshape(-1, 6)
    ends = arcs.x[:, 1:].reshape(-1, 6)
    dts = np.tile(np.diff(t), 12)
    perm = C._lane_order(EARTH_MOON, starts, ends, dts)
    assert np.array_equal(np.sort(perm), np.arange(60))
    interval = np.tile(np.arange(5), 12)[perm]
    assert np.all(interval.reshape(5, 12) == interval.reshape(5, 12)[:, :1])
    # the estimate grows towards the faster, closer intervals
    r1, r2 = EARTH_MOON.distances(starts)
    est = np.abs(dts) * np.linalg.norm(starts[:, 3:], axis=1) / np.minimum(r1, r2)
    r1e, r2e = EARTH_MOON.distances(ends)
    est = np.maximum(est, np.abs(dts) * np.linalg.norm(ends[:, 3:], axis=1) / np.minimum(r1e, r2e))
    assert np.all(np.diff(est[perm]) >= 0)


@pytest.mark.parametrize("j, k", [(0, 0), (7, 3), (11, 4)])
def test_sorted_stt_matches_central_differences_of_the_stm(perturbed, j, k):
    """``stt[j, k]`` (observer j, interval k) against central differences of the STM from the same interval start:
    :math:`\\Psi_{a,b,c} = \\partial\\Phi_{a,b}/\\partial x_{0,c}` (a transposed tensor, first two indices swapped,
    fails: the STM is far from symmetric)."""
    t, X0, arcs = perturbed
    start = arcs.x[j, k]
    np.testing.assert_allclose(start, propagate(EARTH_MOON, X0[j], t).x[k], rtol=0, atol=1e-13)
    fd = stt_finite_difference(EARTH_MOON, start, float(t[k + 1] - t[k]), 1e-6)
    psi = arcs.stt[j, k]
    assert np.max(np.abs(psi - np.swapaxes(psi, 1, 2))) == 0.0
    rel = np.max(np.abs(psi - fd)) / np.max(np.abs(fd))
    assert rel <= 1e-6, rel
    assert np.max(np.abs(np.swapaxes(psi, 0, 1) - fd)) / np.max(np.abs(fd)) > 1e-2

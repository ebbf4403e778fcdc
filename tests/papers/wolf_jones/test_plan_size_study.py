"""The plan-size sweep of Wolf & Jones test case 1 (issue 22, item 2): unit readings, the DRO's size, the
"not immediately apparent" test, a small sweep against invariants of the weighted-sum front, executor
independence and the figure."""

import dataclasses
from concurrent.futures import ThreadPoolExecutor

import matplotlib.pyplot as plt
import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import propagate
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import figures
from cislunar.papers.wolf_jones import plan_size_study as ps
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.publish import plotting

ADOPTED, MPS = ps.ADOPTED_NORMALISATION, "total, m/s"
SMALL = dict(normalisations=[ADOPTED, MPS], readings=[ps.ADOPTED_READING], alphas=(5e-3, 2e-2))


@pytest.fixture(scope="module")
def small():
    return ps.plan_size_sweep(10, **SMALL)


def test_process_noise_readings_in_normalised_units():
    assert ps.q_reading_nd(ps.ADOPTED_READING, em) == pytest.approx(wj.PROCESS_NOISE_PSD_ND, rel=1e-12)
    # literal: 1e-11 km^2/s^3 with L = 384,400 km and T = 375,190.25852 s, by hand
    assert ps.q_reading_nd(ps.LITERAL_READING, em) == pytest.approx(1e-11 * 375190.25852**3 / 384400.0**2, rel=1e-12)
    assert ps.q_reading_nd(ps.LITERAL_READING, em) / ps.q_reading_nd(ps.ADOPTED_READING, em) == pytest.approx(
        1e-11 / 2.8e-17, rel=0.01)
    with pytest.raises(ValueError, match="reading"):
        ps.q_reading_nd("1e-11 furlongs", em)


def test_dro_size_is_the_largest_moon_distance():
    sc = wj.test_case_1()
    r = ps.dro_size_km(sc)
    # independent: the Moon distance on a finer grid from scipy-free sampling of one period
    x = propagate(sc.system, sc.observer_x0, np.linspace(0.0, sc.period, 8001)).x
    d = np.linalg.norm(x[:, :3] - [1 - sc.system.mu, 0, 0], axis=1) * sc.system.length_unit_km
    assert r == pytest.approx(d.max(), rel=1e-5) and r <= d.max()
    assert r == pytest.approx(117_553, abs=5)  # the number
    # larger than the x-axis crossing distance at t = 0 (a DRO is elongated along y)
    assert r > abs(sc.observer_x0[0] - (1 - sc.system.mu)) * sc.system.length_unit_km


def _row(norm, alpha, dep, imp, ok=True):
    return ps.PlanSizeRow(norm, "q", 1.0, 1e-11, alpha, ok, imp, 1.0, dep, 1e5, 3, "" if ok else "failed")


def _study(rows, fraction=0.05, size=100_000.0):
    return ps.PlanSizeStudy(tuple(rows), _row("b", 0.0, 10.0, 1.0), tuple(dict.fromkeys(r.normalisation for r in rows)),
                            ("q",), (5e-3, 2e-2), 10, size, fraction, 0.0)


def test_fit_rule_on_the_threshold():
    """5 % of a 100,000-km DRO: 5,000 km passes, 5,001 does not; the larger weight must depart and spend more."""
    st = _study([_row("a", 5e-3, 1000.0, 5.0), _row("a", 2e-2, 5000.0, 9.0),  # fits, on the threshold
                 _row("b", 5e-3, 1000.0, 5.0), _row("b", 2e-2, 5001.0, 9.0),  # just too large
                 _row("c", 5e-3, 3000.0, 5.0), _row("c", 2e-2, 2000.0, 9.0),  # departs less at 2e-2
                 _row("d", 5e-3, 1000.0, 5.0), _row("d", 2e-2, 2000.0, 4.0),  # spends less at 2e-2
                 _row("e", 5e-3, 1000.0, 5.0), _row("e", 2e-2, np.nan, np.nan, ok=False)])
    assert st.threshold_km == 5000.0
    assert [st.fits(n, "q") for n in "abcde"] == [True, False, False, False, False]
    assert [st.small(n, "q") for n in "abcde"] == [True, False, True, True, False]
    assert st.fitting == [("a", "q")]
    np.testing.assert_array_equal(st.departures(2e-2)[:, 0], [5000.0, 5001.0, 2000.0, 2000.0, np.nan])
    with pytest.raises(ValueError, match="no row"):
        st.row("z", "q", 5e-3)


def test_small_sweep_obeys_the_weighted_sum_front(small):
    """m/s total is c = 1024.5: its information weight is 1/1024 of the adopted one at the same alpha_h, so its
    plans spend less and gather less (optimal value of a weighted sum: impulse and MI non-decreasing in the
    information weight), and no plan spends less than the minimum-impulse plan."""
    b = small.baseline
    assert b.converged and b.alpha == 0.0
    assert len(small.rows) == 4 and all(r.converged for r in small.rows)
    for a in small.alphas:
        ad, ms = small.row(ADOPTED, ps.ADOPTED_READING, a), small.row(MPS, ps.ADOPTED_READING, a)
        assert ms.control_scale == pytest.approx(1e3 * em.velocity_unit_km_s) and ad.control_scale == 1.0
        assert b.impulse_mps * (1 - 1e-6) <= ms.impulse_mps <= ad.impulse_mps
        assert ms.mi_nats <= ad.mi_nats + 1e-9
        assert ms.departure_km <= ad.departure_km
    # every plan must end on the printed terminal state, off the reference DRO: the departure is at least that
    sc = wj.test_case_1()
    end_gap = np.linalg.norm(propagate(sc.system, sc.observer_x0, [0.0, sc.duration]).x[-1, :3]
                             - sc.observer_xf[:3]) * sc.system.length_unit_km
    assert all(r.departure_km >= 0.99 * end_gap for r in small.rows + (b,))
    assert all(r.moon_distance_km >= 0.9 * small.dro_size_km for r in small.rows)
    text = small.summary()
    assert "fit the text" in text and MPS in text


def test_executor_gives_the_same_rows(small):
    with ThreadPoolExecutor(2) as ex:
        threaded = ps.plan_size_sweep(10, executor=ex, **SMALL)
    assert threaded.rows == small.rows and threaded.baseline == small.baseline


def test_known_plans_stand_for_the_solves_bit_for_bit(small):
    # notebook 05 hands the sweep's and the multi-start's plans from the ballistic DRO to the sweep instead of solving
    # them again: they must be the plans the sweep would solve (same rows, run times aside), and be used
    sc = wj.test_case_1()
    t, k_ws, _ = sc.node_times(10, 1.0)
    solver = wj.ScenarioSolver(sc, t, k_ws, information=sc.information_model(), settings=scvx.SCvxSettings())
    x_ball, u_ball = sc.ballistic_guess(t)
    known = {a: solver(a, x_ball, u_ball) for a in (0.0, 5e-3)}
    reused = ps.plan_size_sweep(10, known=known, **SMALL)
    assert reused.rows == small.rows and reused.baseline == small.baseline
    fake = {5e-3: dataclasses.replace(known[5e-3], impulse=2 * known[5e-3].impulse)}  # a known plan is not re-solved
    doubled = ps.plan_size_sweep(10, known=fake, normalisations=[ADOPTED], readings=[ps.ADOPTED_READING],
                                 alphas=(5e-3,))
    assert doubled.rows[0].impulse_mps == pytest.approx(2 * small.rows[0].impulse_mps, rel=1e-12)
    with pytest.raises(ValueError, match="known"):
        ps.plan_size_sweep(10, known={2e-2: known[5e-3]}, **SMALL)


def test_figure_has_units(small):
    fig = figures.departure_figure(small)
    try:
        assert plotting.axis_label_problems(fig) == []
        assert len(fig.axes[0].lines) >= 3
    finally:
        plt.close(fig)


def test_bad_arguments_are_named():
    with pytest.raises(ValueError, match="normalisations"):
        ps.plan_size_sweep(10, normalisations=["per fortnight"])
    with pytest.raises(ValueError, match="alphas"):
        ps.plan_size_sweep(10, alphas=(0.0, 2e-2))
    with pytest.raises(ValueError, match="executor"):
        ps.plan_size_sweep(10, executor=object())
    with pytest.raises(TypeError, match="readings"):
        ps.plan_size_sweep(10, readings="adopted")
    with pytest.raises(ValueError, match="n_nodes"):
        ps.plan_size_sweep(3)

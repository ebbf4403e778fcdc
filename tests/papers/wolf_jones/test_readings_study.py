"""Wolf & Jones under every process-noise reading (readings_study): the adopted reading reproduces the scenario's
own CRLB, the CRLB grows with the PSD (Riccati monotonicity), the verdict statistics against hand computations, and
the row-selection rule of claims/process_noise_readings."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from cislunar.cr3bp.propagation import propagate
from cislunar.papers.wolf_jones import figures
from cislunar.papers.wolf_jones import readings_study as rs
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.papers.wolf_jones.claims.process_noise_readings import CLAIMS, CORR_LIMIT, WEAK_FACTOR
from cislunar.publish import plotting


@pytest.fixture(scope="module")
def case2():
    """Test case 2 and three window-start states: the ballistic one and two pushed out of the plane (no SCvx)."""
    sc = wj.test_case_2()
    x = propagate(sc.system, sc.observer_x0, [0.0, sc.window[0]]).x[-1]
    dv = np.array([0, 0, 0, 0, 0, 1.0]) * 2e-3  # 2e-3 LU/TU ~ 2 m/s out of plane
    xs = np.array([x, x + dv, x + 3 * dv])
    return sc, xs, rs.evaluate_readings(sc, [0.0, 1e-3, 1e-2], xs, dv_mps=[1.0, 2.0, 3.0], mi_planned=[1.0, 2.0, 3.0])


def test_the_adopted_reading_is_the_scenarios_own_crlb(case2):
    sc, xs, st = case2
    ref = [wj.evaluate_crlb(sc, x) for x in xs]  # the scenario's q, no override
    row = st.adopted
    assert row.q_km2_s3 == pytest.approx(sc.q * sc.system.length_unit_km**2 / sc.system.time_unit_s**3, rel=1e-12)
    np.testing.assert_allclose(row.rms_km, np.stack([c.rms_km for c in ref]), rtol=1e-10)
    np.testing.assert_allclose(row.mi, [c.mutual_information for c in ref], rtol=1e-10)
    np.testing.assert_allclose(row.terminal_obs_km, [c.terminal_rms_km[0] for c in ref], rtol=1e-10)
    np.testing.assert_allclose(row.terminal_tgt_km, [np.mean(c.terminal_rms_km[1:]) for c in ref], rtol=1e-10)
    np.testing.assert_allclose(row.mean_obs_km, [np.mean(c.rms_km[0]) for c in ref], rtol=1e-10)


def test_the_crlb_grows_with_the_psd(case2):
    """Riccati monotonicity: the same P0 and measurements with a larger Q give a larger posterior covariance at every
    time, so the position RMS is ordered like the PSDs of the readings (and the literal one is far the largest)."""
    _, _, st = case2
    order = np.argsort([r.q_km2_s3 for r in st.rows])
    rms = np.stack([st.rows[i].rms_km for i in order])  # (readings by increasing q, plans, objects, times)
    assert np.all(np.diff(rms, axis=0) >= -1e-9 * rms[1:])
    assert np.all(st.rows[order[-1]].terminal_obs_km > 1.3 * st.rows[order[-2]].terminal_obs_km)


def _rank(v):
    return np.argsort(np.argsort(v)).astype(float)


def _study(terminal_obs, mi, labels=("literal", "x adopted", "small"), q=(1e-11, 2.8e-17, 1e-22)):
    """A hand-built study: one row per reading, two objects, two times, the last time's observer RMS given."""
    rows = []
    for lab, qq, term, m in zip(labels, q, terminal_obs, mi):
        term = np.asarray(term, float)
        rms = np.zeros((term.size, 2, 2))
        rms[:, 0, 0], rms[:, 0, 1] = 2 * term, term
        rms[:, 1, 0], rms[:, 1, 1] = 4 * term, 2 * term
        rows.append(rs.ReadingRow(lab, qq, np.array([0.0, 1.0]), rms, np.asarray(m, float)))
    n = len(terminal_obs[0])
    return rs.ReadingsStudy(2, tuple(np.linspace(0, 1e-2, n)), np.arange(n, dtype=float),
                            np.arange(n, dtype=float), tuple(rows))


def test_verdict_statistics_against_hand_computations():
    term = [100.0, 20.0, 30.0, 10.0]
    mi = [1.0, 2.0, 4.0, 3.0]
    st = _study([term] * 3, [mi] * 3)
    r = st.rows[1]
    assert st.weak_ratio(r) == pytest.approx(100.0 / 30.0)  # against the worst (largest) alpha_h > 0 RMS
    assert st.weak_ratio_mean(r) == pytest.approx(150.0 / 45.0)  # window mean of (2t, t) is 1.5 t
    d = _rank(mi) - _rank(term)
    rho = 1 - 6 * np.sum(d**2) / (4 * (16 - 1))  # Spearman without ties
    assert st.ranks(r) == pytest.approx((rho, rho))
    assert rho == pytest.approx(-0.4) and rho > CORR_LIMIT and not st.corr_holds(r)
    assert st.weak_holds(r) == (100.0 / 30.0 >= WEAK_FACTOR)


def test_the_row_rule_every_reading_or_the_tuned_adopted_row():
    good_term, good_mi = [100.0, 10.0, 5.0, 2.0], [1.0, 2.0, 3.0, 4.0]
    bad_term = [100.0, 50.0, 60.0, 70.0]  # ratio 100/70 < 5, MI rises with RMS: both fail
    # holds under all three: the "_every" rows on the worst values
    st = _study([good_term, [100.0, 8.0, 4.0, 1.0], good_term], [good_mi] * 3)
    m = st.measurements()
    assert set(m) == {"case2_weakly_observable_every", "case2_mi_correlation_every"}
    assert st.conclusions() == {"weakly_observable": [], "mi_correlation": []}
    assert m["case2_weakly_observable_every"].value == pytest.approx(10.0)  # min over readings: 100/10, not 100/8
    assert CLAIMS["case2_weakly_observable_every"].judge(m["case2_weakly_observable_every"].value).status == \
        "reproduced"
    # fails under the literal reading only: the tuned "_adopted" rows on the adopted value, naming the literal one
    st = _study([bad_term, [100.0, 8.0, 4.0, 1.0], good_term], [good_mi] * 3)
    m = st.measurements()
    assert set(m) == {"case2_weakly_observable_adopted", "case2_mi_correlation_adopted"}
    w = m["case2_weakly_observable_adopted"]
    assert w.value == pytest.approx(100.0 / 8.0) and "literal" in w.note.split(";")[0] and "small" not in w.note
    assert st.conclusions() == {"weakly_observable": [st.rows[0].name], "mi_correlation": [st.rows[0].name]}
    v = CLAIMS["case2_weakly_observable_adopted"].judge(w.value, note=w.note)
    assert v.status == "consistent (tuned)"
    assert CLAIMS["case2_mi_correlation_adopted"].judge(m["case2_mi_correlation_adopted"].value).status == \
        "consistent (tuned)"
    # fails under the adopted one too: still the adopted row, which then differs
    st = _study([good_term, bad_term, good_term], [good_mi] * 3)
    w = st.measurements()["case2_weakly_observable_adopted"]
    assert CLAIMS["case2_weakly_observable_adopted"].judge(w.value, reason=w.reason).status == "differs"


def test_the_study_pickles_and_draws(case2):
    sc, _, st = case2
    back = pickle.loads(pickle.dumps(st))
    np.testing.assert_array_equal(back.rows[0].rms_km, st.rows[0].rms_km)
    fig = figures.figure_readings(st, sc.system, [0.0, 1e-2])
    assert plotting.axis_label_problems(fig) == []
    assert len(fig.axes) == 2 * len(st.rows)
    assert "adopted" in st.summary()


def test_bad_input_is_refused_by_name(case2):
    sc, xs, _ = case2
    with pytest.raises(ValueError, match="alphas"):
        rs.evaluate_readings(sc, [0.0, 0.0, 1e-2], xs)
    with pytest.raises(ValueError, match="x_window_starts"):
        rs.evaluate_readings(sc, [0.0, 1e-2], xs)
    with pytest.raises(ValueError, match="readings"):
        rs.evaluate_readings(sc, [0.0], xs[:1], readings={"a": 1e-11})
    with pytest.raises(TypeError, match="scenario"):
        rs.evaluate_readings("case 2", [0.0], xs[:1])

"""What notebooks 11 and 12 print and the rows they judge (cislunar.papers.nychka_bhattacharya.readout)."""

import numpy as np
import pytest

from cislunar.estimation import lpv
from cislunar.papers.nychka_bhattacharya import observer_simulation as obs
from cislunar.papers.nychka_bhattacharya import readout
from cislunar.papers.nychka_bhattacharya import robust as rbm
from cislunar.papers.nychka_bhattacharya import sensing_precision as sp
from cislunar.papers.nychka_bhattacharya.claims.observer_simulation import CLAIMS as CLAIMS_12
from cislunar.papers.nychka_bhattacharya.claims.sensing_precision import CLAIMS as CLAIMS_11
from cislunar.papers.nychka_bhattacharya.scenarios import paper_scenario


def test_judged_computes_the_status_from_the_declared_claim():
    r = readout.Readout("x", {"lpv_exact": readout.Measurement(1e-15), "eq23_d": readout.Measurement(19.5)})
    assert str(r) == "x"
    assert [v.status for v in r.judged(CLAIMS_11)] == ["reproduced", "differs"]
    with pytest.raises(KeyError, match="no declared claim"):
        readout.Readout(rows={"not_a_claim": readout.Measurement(1.0)}).judged(CLAIMS_11)


def test_notebook_11_readouts_on_a_small_scenario():
    sc = paper_scenario(n_samples=300)
    ex = sp.exactness_checks(lpv.CR3BPLPV(), 50, np.random.default_rng(0))
    r1, r2 = readout.dynamics(ex), readout.sensors(ex)
    assert "over 50 states" in r1.text
    assert [v.status for v in r1.judged(CLAIMS_11) + r2.judged(CLAIMS_11)] == ["reproduced", "reproduced", "differs"]
    r3 = readout.scenario(sc)
    assert r3.text.count("\n") == 6  # source line and six rho bounds
    assert r3.rows["orbit"].value.startswith("2:1, T = ")
    assert r3.rows["vertices"].value == 64
    assert "km/s^2" in readout.disturbance().text
    bw = sp.BandwidthStudy(np.array([200.0, 1000.0]), np.array([0.07, 0.076]), np.array([100.0, 800.0]),
                           ("optimal", "optimal"), 0.96, 0.0776)
    rb = readout.bandwidth(bw)
    assert rb.text.count("\n") == 1 and "0.0700 deg (R=200) -> 0.0760 deg (R=1000)" in rb.rows["bandwidth"].shown
    tc = sp.TradeCurve(np.array([3e-4, 3e-2]), {}, {}, {"h2": -0.99, "hinf": -1.0})
    assert readout.trade_curve(tc).rows["trade_curve"].note == "2 gammas from 115 to 11500 km"


def test_notebook_12_rows_cover_every_claim():
    sc = paper_scenario(n_samples=300)
    od = obs.observer_designs(sc, 3, np.random.default_rng(0))
    sim = obs.simulate_fig3(sc, od, 0.01, 0.1, 0.1, np.random.default_rng(1))
    cv = obs.convergence_study(sc, od, sim, 0.1, e0_scales=(1.0,))
    al = obs.allowance_at(od, 0.01)
    ww = obs.window_rerun(sc, od, sim, 0.02, 0.1, 0.1, np.random.default_rng(2))
    se = rbm.scheduling_error(sc, 0.1, 2, np.random.default_rng(3))
    rd = rbm.robust_designs(sc, se, 0.0373, 2, np.random.default_rng(4), iters=2)
    ws = rbm.simulate_window(sc, od, rd, 0.1, np.random.default_rng(5))
    win = readout.window(ws, rd, od)
    parts = [readout.observer_gains(od, 0.0013), readout.allowance_at_dt(al, 0.1), readout.converges(cv, sim),
             readout.comparison(sim, ww, od, al, 0.1), win]
    assert readout.scheduling_error(se).text and readout.robust_designs(rd).text.count("\n") == 2
    assert "no_range" not in win.rows  # measured by obs.RangeFree (tests/.../test_observer_simulation.py)
    assert win.rows["fig3_233"].value == all(ws.holds("nominal", n, "large") for n in ("h2", "hinf"))
    # the accuracy rows are judged by the Fig3Accuracy given (default: the simulation's own interval)
    acc = obs.Fig3Accuracy.measure({"x": (sim.t, {n: sim.runs[n].position_error for n in cv.level}),
                                    "y": (ws.t, {n: ws.errors[("nominal", n, "large")] for n in cv.level})},
                                   cv.level, sim.period)
    both = readout.converges(cv, sim, acc=acc)
    assert [both.rows[f"{n}_converges"].value for n in ("h2", "hinf")] == [acc.holds("h2"), acc.holds("hinf")]
    assert "x: below 500 km" in both.rows["h2_converges"].shown and "y: below 625 km" in both.rows["hinf_converges"].shown
    keys = [k for p in parts for k in p.rows] + ["no_range"]  # the range-free row comes from obs.RangeFree
    assert sorted(keys) == sorted(CLAIMS_12)  # every declared row, once
    assert all(v.status for p in parts for v in p.judged(CLAIMS_12))
    # the shown comparison follows the numbers: per-sample H2 allowance against H-infinity
    row = parts[1].rows["ordering_dt"]
    assert (">" in row.shown) == (al.h2_per_sample_deg > al.hinf_deg)
    for text in (readout.measurements(sim, sc).text, readout.convergence(cv, sim).text,
                 readout.convergence_time(cv, sim).text,
                 readout.line_crossings(obs.line_crossings(sim, 0.05), sim).text):
        assert text

"""The robust designs of notebook 12 (cislunar.papers.nychka_bhattacharya.robust): the exact error decomposition,
the widened polytope, the robust LMI's bound on sampled parameters and the 233-min re-run, on small sizes."""

import dataclasses

import numpy as np
import pytest

from cislunar.estimation import lpv
from cislunar.papers.nychka_bhattacharya import observer_simulation as obs
from cislunar.papers.nychka_bhattacharya import robust as rb
from cislunar.papers.nychka_bhattacharya.scenarios import fig1_scene, paper_scenario

DT_233 = 0.0373  # TU, about the interval at which the H2 design allows 0.1 deg per sample


@pytest.fixture(scope="module")
def setup():
    sc = paper_scenario(n_samples=300)
    od = obs.observer_designs(sc, 3, np.random.default_rng(0))
    se = rb.scheduling_error(sc, 0.1, 4, np.random.default_rng(1))
    rd = rb.robust_designs(sc, se, DT_233, 10, np.random.default_rng(2), iters=4)
    return sc, od, se, rd


def test_error_decomposition_is_exact():
    """e' of the observer scheduled on rho_hat equals (A(rho_hat) + L C(rho_hat)) e + delta_f + L (delta_y + n),
    checked against the two vector fields at random states, estimates, parameters and gains (no linearisation)."""
    m = lpv.CR3BPLPV()
    rng = np.random.default_rng(5)
    for _ in range(20):
        x = np.r_[rng.uniform(-0.8, 0.8, 2) + [0.1, 0.3], rng.uniform(-1, 1, 2)]
        xh = x + 0.05 * rng.standard_normal(4)
        rho_hat = m.rho(x[:2] + 0.02 * rng.standard_normal(2)) * (1 + 0.01 * rng.standard_normal(6))
        L = rng.standard_normal((4, 6))
        n = 1e-3 * rng.standard_normal(6)
        y = m.measure(x) + n
        xdot = m.f(x)
        xhdot = (m.A(rho_hat) + L @ m.C(rho_hat)) @ xh - L @ y + m.b(rho_hat) + L @ m.d(rho_hat)
        df, dy = rb.parameter_errors(m, x, rho_hat)
        pred = (m.A(rho_hat) + L @ m.C(rho_hat)) @ (x - xh) + df + L @ (dy + n)
        assert np.allclose(xdot - xhdot, pred, rtol=1e-10, atol=1e-12)
        assert np.allclose(df[:2], 0.0)  # the gravity error is an acceleration


def test_widened_box_contains_true_and_triangulated_parameters(setup):
    sc, _, se, _ = setup
    assert np.all(se.box.contains(sc.rho))  # the true parameters along the orbit
    assert np.all(se.box.lower <= sc.box.lower) and np.all(se.box.upper >= sc.box.upper)
    # fresh triangulations (another seed) fall inside about as often as the coverage says (per parameter 99.9 %)
    m, x = sc.model, sc.states
    t1, t2 = m.angles(x)
    rng = np.random.default_rng(11)
    th1, th2 = t1 + np.radians(0.1) * rng.standard_normal(t1.size), t2 + np.radians(0.1) * rng.standard_normal(t2.size)
    ok = np.abs(np.sin(th1 + th2)) >= 0.04
    assert np.mean(se.box.contains(m.rho_from_angles(th1[ok], th2[ok]))) > 0.97
    assert se.inside > 0.97 and 0.9 < se.triangulated <= 1.0
    # the gravity error the nominal design ignores is far above its disturbance level (1e-3 LU/TU^2)
    assert se.s_f > 10 * 1e-3 and se.s_y > np.radians(0.1)


def test_robust_bound_holds_on_sampled_parameters_inside_the_box(setup):
    """Frozen-parameter check of the robust LMI without the solver: at random parameters in the widened box (and its
    vertices), A + LC is Hurwitz and the norm from the normalised input (noise at the sensor's precision and the two
    scheduling-error inputs) to the position error stays below gamma*."""
    sc, _, se, rd = setup
    m = sc.model
    for n, d in rd.designs.items():
        v = lpv.verify_observer(m, d, se.box, 40, np.random.default_rng(3))
        assert v.hurwitz and v.worst < rd.gamma_star[n] * (1 + 1e-5), (n, v.worst, rd.gamma_star[n])
        # the sensor is precise enough: the design's required precision does not exceed the sensor's
        assert np.max(d.kappa[:2]) <= rd.kappa_sensor[n] * (1 + 1e-9)
        assert rd.guarantee[n] == pytest.approx(np.sqrt(3) * rd.gamma_star[n])
        # the bisection ends at the least bound: a tenth below it the sensor no longer suffices
        lower = d.gamma * 0.9
        lmi = lpv.PrecisionLMI.for_cr3bp(m, se.box.vertices(), n, disturbance=(
            np.hstack([lpv.default_disturbance()[0], np.vstack([np.zeros((2, 4)), np.c_[np.eye(2), np.zeros((2, 2))]])]),
            np.diag([1e-3, 1e-3] + [se.s_f * (np.sqrt(DT_233) if n == "h2" else 1.0) / np.sqrt(2)] * 2
                    + [se.s_y * (np.sqrt(DT_233) if n == "h2" else 1.0) / np.sqrt(2)] * 2),
            np.c_[np.zeros((6, 4)), np.vstack([np.eye(2), np.zeros((4, 2))])]), sensors=[0, 1],
            **({"pole_radius": 1000.0} if n == "hinf" else {}))
        try:
            k_low = np.max(lmi.solve(lower).kappa[:2])
        except lpv.InfeasibleLMIError:
            k_low = np.inf
        assert k_low > rd.kappa_sensor[n]


def test_window_study_runs_and_guarantees(setup):
    sc, od, _, rd = setup
    ws = rb.simulate_window(sc, od, rd, 0.3, np.random.default_rng(4))
    km_keys = {(d, n, s) for d in ("nominal", "nominal, exact rho", "robust") for n in ("h2", "hinf")
               for s in ("large", "small")}
    assert set(ws.errors) == km_keys
    assert ws.e0["small"] == pytest.approx(rb.SMALL_E0_SCALE * ws.e0["large"])
    for key, e in ws.errors.items():
        assert e.shape == ws.t.shape and np.isclose(e[0], ws.e0[key[2]])
    # at dt_233 the nominal H2 guarantee is gamma kappa sigma sqrt(dt), the robust one sqrt(3) gamma*
    h2 = od.designs["h2"]
    assert ws.guarantee[("nominal", "h2")] == pytest.approx(lpv.guaranteed_error_rms(h2, 0.1, DT_233))
    assert ws.guarantee[("robust", "hinf")] == rd.guarantee["hinf"]
    assert ws.holds("robust", "h2") == (ws.rms("robust", "h2") <= rd.guarantee["h2"])
    assert 0.0 <= ws.inside <= 1.0 and all(p > 0 for p in ws.posterior.values())
    rr = ws.as_rerun()
    assert rr.n == ws.t.size and set(rr.median) == {"h2", "hinf"}
    with pytest.raises(ValueError, match="design, norm, start"):
        ws.rms("robust", "h3")


def test_fix_following_detects_a_one_sample_lag_and_nothing_else():
    """An error that is the previous sample's fix error scores correlation 1 and RMS ratio 1; the same error without
    the lag (or a scaled copy) does not pass as following."""
    rng = np.random.default_rng(7)
    t = np.linspace(0.0, 1.0, 400)
    fix = np.abs(rng.normal(size=t.size))
    fix[50] = np.nan  # a sample near the Earth-Moon line: left out, not propagated
    lagged = np.concatenate([[3.0], np.nan_to_num(fix[:-1], nan=1.0)])
    errors = {("nominal", "hinf", "large"): lagged, ("robust", "hinf", "large"): 2.0 * np.nan_to_num(fix, nan=1.0)}
    ws = rb.WindowStudy(t, np.zeros((t.size, 4)), errors, {}, {}, 1.0, {}, 0.01, 1.0, fix)
    c, r = ws.fix_following("nominal", "hinf")
    assert c == pytest.approx(1.0) and r == pytest.approx(1.0)
    c, r = ws.fix_following("robust", "hinf")
    assert abs(c) < 0.3  # same sample, not the one before: independent draws
    with pytest.raises(ValueError, match="design, norm, start"):
        ws.fix_following("robust", "h2")


def test_fix_residual_is_the_rms_of_the_lagged_vector_difference():
    """An error that is the previous sample's fix plus an independent d of known RMS gives fix_residual = RMS|d|
    (lag 1) and about sqrt(2 RMS|f|^2 + RMS|d|^2) against the same sample's fix (lag 0); NaN fixes are left out,
    the first 10 % of the run too; the vectors must match the norms the study stores."""
    rng = np.random.default_rng(11)
    t = np.linspace(0.0, 1.0, 4000)
    fix = rng.normal(size=(t.size, 2))
    fix[100] = np.nan
    d = 0.1 * rng.normal(size=(t.size, 2))
    err = np.vstack([[[5.0, 5.0]], np.nan_to_num(fix[:-1], nan=9.0)]) + d
    errors = {("nominal", "hinf", "large"): np.hypot(*err.T)}
    ws = rb.WindowStudy(t, np.zeros((t.size, 4)), errors, {}, {}, 1.0, {}, 0.01, 1.0, np.hypot(*fix.T), fix,
                        {("nominal", "hinf", "large"): err})
    keep = ws.settled[1:] & np.isfinite(fix[:-1, 0])
    assert ws.fix_residual("nominal", "hinf") == pytest.approx(np.sqrt(np.mean(np.sum(d[1:][keep] ** 2, -1))), rel=1e-12)
    assert ws.fix_residual("nominal", "hinf", lag=0) == pytest.approx(np.sqrt(2 * 2.0 + 0.02), rel=0.05)
    with pytest.raises(ValueError, match="design, norm, start"):
        ws.fix_residual("robust", "hinf")
    with pytest.raises(ValueError, match="lag"):
        ws.fix_residual("nominal", "hinf", lag=t.size)
    bare = rb.WindowStudy(t, np.zeros((t.size, 4)), errors, {}, {}, 1.0, {}, 0.01, 1.0, np.hypot(*fix.T))
    with pytest.raises(ValueError, match="fix_vector"):
        bare.fix_residual("nominal", "hinf")


def test_window_study_hinf_error_follows_the_angle_fix(setup):
    """At 233 min the Hinf gains (||L|| dt >> 1) put the estimate on the previous sample's angle-only fix: the
    lagged vector difference is below the nominal Hinf guarantee and well below the same-sample difference."""
    sc, od, _, rd = setup
    ws = rb.simulate_window(sc, od, rd, 0.3, np.random.default_rng(4))
    assert ws.fix_error.shape == ws.t.shape and np.nanmax(ws.fix_error) > 0
    c, r = ws.fix_following("nominal", "hinf")
    assert c > 0.9 and 0.8 < r < 1.3
    for key, vec in ws.error_vectors.items():
        np.testing.assert_allclose(np.hypot(*vec.T), ws.errors[key], rtol=1e-12)
    np.testing.assert_allclose(np.hypot(*ws.fix_vector.T), ws.fix_error, rtol=1e-12)
    lag1 = ws.fix_residual("nominal", "hinf")
    assert lag1 < ws.guarantee[("nominal", "hinf")] and lag1 < 0.5 * ws.fix_residual("nominal", "hinf", lag=0)


def test_fig1_scene_places_platforms_on_the_orbit():
    sc = paper_scenario(n_samples=200)
    scene = fig1_scene(sc, 4, n_samples=50)
    assert scene.platforms.shape == (4, 4) and scene.rso.shape == (4,)
    # every platform lies on the platform orbit (Jacobi constant of the orbit) and the first one at its start
    jac = sc.model.system.jacobi(sc.model.spatial(scene.platforms))
    assert np.allclose(jac, sc.model.system.jacobi(sc.orbit.x0), atol=1e-9)
    assert np.allclose(scene.platforms[0], sc.model.planar(sc.orbit.x0))


@pytest.mark.parametrize("rso, name, kind", [
    (None, "rso must be a", TypeError), (3.0, "rso must be a", TypeError), (object(), "rso must be a", TypeError),
    ("abc", "rso must be a", TypeError), (np.array(3.0), "rso must be a", TypeError),
    (np.ones((3, 2)), "rso must be a", TypeError), ((3, 1), "rso must hold 3", ValueError),
    ((3.5, 1, 0.3), r"rso\[0\] \(p\) must be an integer", TypeError),  # refused, not truncated to 3:1
    ((3, "1", 0.3), r"rso\[1\] \(q\) must be an integer", TypeError),
    ((3, 1, np.nan), r"rso\[2\] \(perigee radius, LU\) must be finite", ValueError),
    ((1, 2, 0.3), r"rso = \(1, 2, 0.3\) is not a resonant orbit", ValueError),
    ((2, 2, 0.3), r"rso = \(2, 2, 0.3\) is not a resonant orbit: p and q", ValueError),
    ((3, 1, 0.95), r"rso = .* perigee_radius must lie in", ValueError),
    ((4, 1, 0.9), r"rso = .* below 2a", ValueError),  # 2a = 0.794 LU for 4:1
])
def test_fig1_scene_refuses_a_bad_rso_by_name(rso, name, kind):
    sc = paper_scenario(n_samples=50)
    with pytest.raises(kind, match=name):
        fig1_scene(sc, 2, rso=rso, n_samples=10)


def test_fig1_scene_takes_rso_as_the_resonance_it_names():
    """A list, an array or integral floats give the same RSO orbit as the tuple (3, 1, 0.3)."""
    sc = paper_scenario(n_samples=50)
    ref = fig1_scene(sc, 2, rso=(3, 1, 0.3), n_samples=10)
    assert ref.labels[1] == "RSO orbit (3:1 resonant)"
    for rso in ([3, 1, 0.3], np.array([3.0, 1.0, 0.3]), (3.0, 1.0, 0.3)):
        scene = fig1_scene(sc, 2, rso=rso, n_samples=10)
        assert scene.labels == ref.labels and np.array_equal(scene.rso_orbit, ref.rso_orbit)
    assert fig1_scene(sc, 2, rso=(2, 1, 0.3), n_samples=10).labels[1] == "RSO orbit (2:1 resonant)"


@pytest.fixture(scope="module")
def small_setup():
    """The 2:1 orbit at 50 samples with its box (and the widened one) narrowed to 8 vertices (LMIs in ~0.1 s)."""
    def narrowed(box):
        lo, hi = box.lower.copy(), box.upper.copy()
        c = 0.5 * (lo + hi)
        lo[3:], hi[3:] = c[3:], c[3:]
        return lpv.ParameterBox(lo, hi, source="8 vertices")

    sc = paper_scenario(n_samples=50)
    sc = dataclasses.replace(sc, box=narrowed(sc.box))
    se = rb.scheduling_error(sc, 0.1, 2, np.random.default_rng(0))
    return sc, dataclasses.replace(se, box=narrowed(se.box))


def test_robust_designs_refuse_an_infeasible_pole_radius_after_a_bounded_search(small_setup, monkeypatch):
    """pole_radius = 2.5 1/TU is below the bandwidth any observer of this box can have: the H-infinity LMI is
    infeasible at every gamma.  The search for gamma* stops at about 1 LU (five solves) and names pole_radius;
    before, it grew gamma fourfold until it overflowed (about 500 solves) and then complained about gamma."""
    sc, se = small_setup
    calls = []
    solve = lpv.PrecisionLMI.solve

    def counted(self, gamma, **kw):
        calls.append((self.norm, gamma))
        if len(calls) > 20:
            raise AssertionError(f"the gamma search did not stop: {len(calls)} solves, last gamma {gamma:g}")
        return solve(self, gamma, **kw)

    monkeypatch.setattr(lpv.PrecisionLMI, "solve", counted)
    with pytest.raises(ValueError, match=r"no gamma up to 1\.33 LU .* hinf LMI is infeasible.* pole_radius=2\.5"):
        rb.robust_designs(sc, se, DT_233, 1, np.random.default_rng(0), pole_radius=2.5, iters=1)
    # H-infinity is searched first, so the refusal comes before any H2 solve
    assert [n for n, _ in calls] == ["hinf"] * 5
    assert [g for _, g in calls] == pytest.approx([4 * rb.GAMMA * 4**k for k in range(5)])
    # a feasible bandwidth bound still gives designs (the search then stops at the first feasible gamma)
    calls.clear()
    rd = rb.robust_designs(sc, se, DT_233, 1, np.random.default_rng(0), pole_radius=1000.0, iters=1)
    assert set(rd.designs) == {"h2", "hinf"} and list(rd.kappa_sensor) == ["h2", "hinf"]
    assert all(g <= 4 * rb.GAMMA for g in rd.gamma_star.values())


def test_robust_designs_name_the_sensor_when_it_is_never_precise_enough(small_setup, monkeypatch):
    """If every gamma's design needs more precision than the sensor has, the refusal names the sensor (serr's
    sigma_deg, dt), not an internal gamma; forced here by making every solved design demand infinite precision."""
    sc, se = small_setup
    solve = lpv.PrecisionLMI.solve

    def greedy(self, gamma, **kw):
        d = solve(self, gamma, **kw)
        return dataclasses.replace(d, kappa=np.full_like(d.kappa, np.inf))

    monkeypatch.setattr(lpv.PrecisionLMI, "solve", greedy)
    with pytest.raises(ValueError, match=r"no gamma up to .* needs a theta1 precision inf > the sensor's .* "
                                         r"\(serr\.sigma_deg=0\.1 deg sampled every dt=0\.0373"):
        rb.robust_designs(sc, se, DT_233, 1, np.random.default_rng(0), iters=1)

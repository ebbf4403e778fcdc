"""Bad input by class (issue 20 item 2, reliability audit 2026-11-25): hypothesis draws new cases of each class.

The audit keeps its cases back and draws new ones of the same classes, so each test here generates cases of one
class across the public functions of the methods wings and requires a clean, named refusal:

* text inside a container (a list of numeric strings) for every array argument of the table's specs;
* numerically singular covariances (rank-deficient PSD matrices rotated out of diagonal form) for every SPD one;
* arcs that dip below a primary's surface between grid points, in every propagation path (including the OCBEs);
* arrays built for another set-up (one epoch more or fewer) given to functions taking several arrays;
* containers holding a state inside a primary;
* sizes that would hang (tiny steps), refused up front with the limit named;
* degenerate CR3BP parameters.

Each test records its cases and outcomes in ``COUNTS``; ``pytest -s`` prints the summary at the end.
"""

from __future__ import annotations

import collections
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_reliability import PLUGINS, SPECS, _resolve, classify

from cislunar.cr3bp import orbits, torus
from cislunar.cr3bp.dynamics import CR3BP
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import ImpactError, propagate
from cislunar.estimation import batched_ocbe, ocbe
from cislunar.guidance import discretization, scvx
from cislunar.sensing import measurements, sites

COUNTS: dict = collections.defaultdict(collections.Counter)
METHOD_WINGS = ("cislunar.cr3bp", "cislunar.sensing", "cislunar.estimation", "cislunar.guidance", "cislunar.utils")


_PLUGIN_MODULES = {p.__name__.removeprefix("reliability_specs_"): [m.__name__ for m in p.MODULES] for p in PLUGINS}


def _wing_module(name: str) -> bool:
    return name.startswith(METHOD_WINGS) and not name.endswith(("lpv", "observers"))


def _in_wings(spec) -> bool:
    if getattr(spec.fn, "_lazy", False):  # a bound method of a cached object
        source = getattr(spec, "source", None)
        if source is not None and not any(_wing_module(m) for m in _PLUGIN_MODULES[source]):
            return False  # a plugin of the paper wings only: decided without building its cached objects
        fn = spec.fn()
    else:
        fn = spec.fn
    return _wing_module(getattr(fn, "__module__", "") or "")


ARRAY_KINDS = ("arr", "state", "grid", "arr_finite", "spd", "spd_batch", "vec", "arr_opt")


def _record(cls, outcome):
    COUNTS[cls]["cases"] += 1
    COUNTS[cls][outcome.split(":")[0]] += 1


# the kinds are looked at first, so a spec with no such argument never builds its cached objects at collection
ARRAY_ARGS = [(s, a) for s in SPECS if set(s.kinds.values()) & set(ARRAY_KINDS) and _in_wings(s)
              for a, k in s.kinds.items() if k in ARRAY_KINDS]
SPD_ARGS = [(s, a) for s, a in ARRAY_ARGS if s.kinds[a] in ("spd", "spd_batch")]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(ARRAY_ARGS), st.booleans(), st.randoms(use_true_random=False))
def test_text_inside_containers_is_refused_by_name(case, all_text, rnd):
    spec, arg = case
    valid = np.asarray(_resolve(spec)[arg], dtype=float)
    if valid.size == 0:
        return
    text = np.vectorize(repr)(valid).astype(object)
    if not all_text:  # one numeric string among numbers
        mixed = valid.astype(object)
        i = rnd.randrange(valid.size)
        mixed.flat[i] = repr(float(valid.flat[i]))
        text = mixed
    bad = text.tolist() if valid.ndim else [text.item()]
    outcome = classify(spec, arg, bad)
    _record("text in containers", outcome)
    assert outcome == "named", f"{spec.label}({arg}={bad!r:.80}): {outcome}"


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(SPD_ARGS), st.integers(0, 2**32 - 1), st.integers(1, 3))
def test_numerically_singular_covariances_are_refused_by_name(case, seed, rank_loss):
    spec, arg = case
    valid = np.asarray(_resolve(spec)[arg], dtype=float)
    n = valid.shape[-1]
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    lam = np.exp(rng.uniform(-3, 3, n)) * float(np.mean(np.diagonal(valid, axis1=-2, axis2=-1)))
    lam[rng.choice(n, size=min(rank_loss, n - 1), replace=False)] = 0.0
    M = Q @ np.diag(lam) @ Q.T
    M = 0.5 * (M + M.T)
    bad = np.broadcast_to(M, valid.shape).copy()
    outcome = classify(spec, arg, bad)
    _record("singular covariances", outcome)
    assert outcome == "named", f"{spec.label}({arg}): {outcome}"


def _dipping_arc(depth_km, speed_km_s, half_hours, incl):
    """A ballistic arc whose perilune lies ``depth_km`` below the lunar surface, sampled only outside the Moon."""
    r = em.km_to_lu(em.secondary_radius_km - depth_km)
    v = speed_km_s / em.velocity_unit_km_s
    peri = np.array([1 - em.mu + r, 0, 0, 0, v * np.cos(incl), v * np.sin(incl)])
    h = float(em.days_to_tu(half_hours / 24.0))
    x0 = propagate(em, peri, np.array([0.0, -h]), impact=False).x[-1]
    xe = propagate(em, peri, np.array([0.0, h]), impact=False).x[-1]
    return x0, xe, np.array([0.0, 2 * h])


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.floats(50.0, 1600.0), st.floats(2.2, 3.5), st.floats(1.0, 4.0), st.floats(-1.2, 1.2),
       st.sampled_from(["propagate", "ocbe_transition", "ocbe_filter_smoother", "ocbe_batch"]))
def test_arcs_below_a_surface_raise_a_named_error_in_every_propagation_path(depth, speed, half_hours, incl, path):
    x0, xe, t = _dipping_arc(depth, speed, half_hours, incl)
    r0 = np.linalg.norm(x0[:3] - em.secondary_position) * em.length_unit_km
    if r0 <= em.secondary_radius_km + 100.0:
        return
    model = measurements.ANGLES_AND_RATES
    obs = np.tile(sites.l2_observer_state(em), (2, 1))
    y = model(obs, np.array([x0, xe]))
    R = np.eye(4) * 1e-10
    try:
        if path == "propagate":
            propagate(em, x0, t)
        elif path == "ocbe_transition":
            ocbe.ocbe_transition(em, x0, t, 1e-6)
        elif path == "ocbe_filter_smoother":
            ocbe.ocbe_filter_smoother(em, t, y, obs, model, R, x0, np.eye(6) * 1e-12, 1e-8, n_sub=2)
        else:
            batched_ocbe.ocbe_batch(em, t, np.stack([y, y]), obs, model, R, np.stack([x0, x0]), np.eye(6) * 1e-12,
                                    1e-8, n_sub=2)
        outcome = "junk"
    except ImpactError:
        outcome = "named"
    except ocbe.FilterDivergenceError as exc:
        outcome = "named" if "ImpactError" in str(exc) and "Moon" in str(exc) else f"other clean: {exc}"
    _record("arcs below a surface", outcome)
    assert outcome == "named", (path, depth, speed, half_hours, incl, outcome)


def _mismatch_cases():
    t = np.linspace(0.0, 0.6, 7)
    x = propagate(em, np.array([0.8, 0, 0, 0, 0.52, 0]), t).x
    u = np.zeros((t.size, 3))
    obs = np.tile(sites.l2_observer_state(em), (t.size, 1))
    model = measurements.ANGLES_AND_RATES
    y = model(obs, x)
    R = np.eye(4) * 1e-10
    P0 = np.eye(6) * 1e-10
    return {
        "foh_discretize": (discretization.foh_discretize, dict(system=em, t=t, x=x, u=u), ("x", "u")),
        "propagate_foh": (discretization.propagate_foh, dict(system=em, x0=x[0], t=t, u=u), ("u",)),
        "impulse": (scvx.impulse, dict(t=t, u=u), ("u",)),
        "solve_scvx": (scvx.solve_scvx, dict(system=em, t_nodes=t, x_guess=x, u_guess=u, u_max=np.full(t.size, 1e-3),
                                             settings=scvx.SCvxSettings(max_iter=1)),
                       ("x_guess", "u_guess", "u_max")),
        "ocbe_filter_smoother": (ocbe.ocbe_filter_smoother,
                                 dict(system=em, t=t, y=y, observer_states=obs, model=model, meas_cov=R, x0=x[0],
                                      P0=P0, control_weight=np.full(t.size - 1, 1e-8), n_sub=2),
                                 ("y", "observer_states", "control_weight")),
        "ocbe_batch": (batched_ocbe.ocbe_batch,
                       dict(system=em, t=t, y=y[None], observer_states=obs, model=model, meas_cov=R, x0=x[:1],
                            P0=P0, control_weight=np.full(t.size - 1, 1e-8), n_sub=2),
                       ("observer_states", "control_weight")),
    }


MISMATCH = _mismatch_cases()


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(sorted(MISMATCH)), st.data(), st.sampled_from([-4, -1, 1, 3]))
def test_arrays_built_for_another_set_up_are_refused_by_name(label, data, delta):
    fn, kw, args = MISMATCH[label]
    arg = data.draw(st.sampled_from(args))
    a = np.asarray(kw[arg])
    axis = 1 if label == "ocbe_batch" and arg == "y" else 0
    n = a.shape[axis] + delta
    bad = np.take(a, np.arange(n) % a.shape[axis], axis=axis)  # epochs dropped or repeated
    try:
        fn(**{**kw, arg: bad})
        outcome = "junk"
    except (ValueError, TypeError) as exc:
        outcome = "named" if arg in str(exc) else f"other clean: {exc}"
    except Exception as exc:  # noqa: BLE001
        outcome = f"crash: {type(exc).__name__}"
    _record("cross-argument sizes", outcome)
    assert outcome == "named", (label, arg, delta, outcome)


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(["Moon", "Earth"]), st.floats(0.0, 0.999), st.floats(-np.pi, np.pi))
def test_containers_refuse_a_state_inside_a_primary(body, frac, angle):
    dro = orbits.correct_symmetric(em, [0.8, 0, 0, 0, 0.52, 0], fix="x0") if not hasattr(
        test_containers_refuse_a_state_inside_a_primary, "dro") else test_containers_refuse_a_state_inside_a_primary.dro
    test_containers_refuse_a_state_inside_a_primary.dro = dro
    centre, radius = ((em.secondary_position, em.secondary_radius) if body == "Moon"
                      else (em.primary_position, em.primary_radius))
    x = np.r_[centre + frac * radius * np.array([np.cos(angle), np.sin(angle), 0.0]), dro.x0[3:]]
    try:
        orbits.PeriodicOrbit(em, x, dro.period, dro.monodromy, dro.closure, label="bad")
        outcome = "junk"
    except ImpactError:
        outcome = "named"
    _record("containers", outcome)
    assert outcome == "named"


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(["torus_from_orbit", "site_grid", "occultation_outages", "mean_range_periods"]),
       st.integers(5, 12))
def test_sizes_that_would_hang_are_refused_up_front(what, exponent):
    tiny = 10.0 ** -exponent
    t0 = time.perf_counter()
    try:
        if what == "torus_from_orbit":
            torus.torus_from_orbit(orbits.nrho_9_2(em), size_km=10.0, step_km=tiny)  # >= 1e5 steps
        elif what == "site_grid":
            sites.site_grid(180.0 / 10 ** (exponent - 2), 360.0 / 10 ** (exponent - 2))
        elif what == "occultation_outages":
            sites.occultation_outages(em, sites.l2_observer_state(em), orbits.nrho_9_2(em), span_days=30.0,
                                      step_s=tiny * 1e4)
        else:
            seed = torus.torus_seed(orbits.nrho_9_2(em), 5, 1.0)
            torus.mean_range(seed, n_theta=10**exponent, n_t=101)
        outcome = "junk"
    except ValueError as exc:
        outcome = "named" if "limit" in str(exc) else f"other clean: {exc}"
    elapsed = time.perf_counter() - t0
    _record("sizes", outcome)
    assert outcome == "named" and elapsed < 5.0, (what, exponent, outcome, elapsed)


@settings(max_examples=80, deadline=None)
@given(st.sampled_from(["mu", "length_unit_km", "time_unit_s"]),
       st.one_of(st.floats(-10, 0), st.floats(0.5, 10, exclude_min=True), st.floats(0, 1e-16),
                 st.just(float("nan")), st.floats(1e16, 1e300), st.floats(5e-324, 1e-7)))
def test_degenerate_cr3bp_parameters_are_refused_by_name(field, value):
    kw = dict(mu=0.0121, length_unit_km=384400.0, time_unit_s=375190.0)
    if field == "mu" and 1.1102230246251566e-16 <= value <= 0.5:
        return  # a valid mass parameter
    if field != "mu" and 1e-6 <= value <= 1e15:
        return
    kw[field] = value
    try:
        CR3BP(**kw)
        outcome = "junk"
    except ValueError as exc:
        outcome = "named" if field in str(exc) else f"other clean: {exc}"
    _record("degenerate CR3BP", outcome)
    assert outcome == "named", (field, value, outcome)


@pytest.fixture(scope="module", autouse=True)
def _summary():
    yield
    if COUNTS:
        print("\nbad input by class (cases: outcomes)")
        for cls, c in COUNTS.items():
            rest = ", ".join(f"{k} {v}" for k, v in sorted(c.items()) if k != "cases")
            print(f"  {cls}: {c['cases']} cases: {rest}")

"""heyoka propagation: STM and STT against finite differences, against scipy, invariants, batch, events."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cislunar.cr3bp import orbits
from cislunar.cr3bp import propagation as pr
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import (
    find_events,
    propagate,
    propagate_scipy,
    propagate_stm,
    propagate_stt,
)

NRHO_GUESS = np.array([1.02202821, 0.0, -0.1821014, 0.0, -0.10327095, 0.0])


@pytest.fixture(scope="module")
def nrho():
    return orbits.nrho_9_2(em)


@pytest.mark.parametrize("t_final", [0.7, 1.5])
def test_stm_matches_central_differences(t_final):
    x0 = NRHO_GUESS
    tr = propagate_stm(em, x0, t_final)
    h = 1e-7
    fd = np.empty((6, 6))
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        fd[:, j] = (propagate(em, x0 + e, t_final).x[-1] - propagate(em, x0 - e, t_final).x[-1]) / (2 * h)
    rel = np.max(np.abs(tr.stm[-1] - fd)) / np.max(np.abs(fd))
    assert rel <= 1e-6


def test_stt_matches_central_differences_of_the_stm():
    x0 = NRHO_GUESS
    t_final = 1.2  # through perilune, where the second-order terms are largest
    tr = propagate_stt(em, x0, t_final)
    psi = tr.stt[-1]
    assert np.max(np.abs(psi - np.swapaxes(psi, 1, 2))) == 0.0  # symmetric by construction
    h = 1e-6
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        fd = (propagate_stm(em, x0 + e, t_final).stm[-1] - propagate_stm(em, x0 - e, t_final).stm[-1]) / (2 * h)
        rel = np.max(np.abs(psi[:, :, j] - fd)) / np.max(np.abs(fd))
        assert rel <= 1e-6, (j, rel)
    # the STM from the order-2 system equals the order-1 STM
    assert np.max(np.abs(tr.stm[-1] - propagate_stm(em, x0, t_final).stm[-1])) < 1e-12 * np.max(np.abs(tr.stm[-1]))


def test_stt_second_order_prediction_beats_first_order():
    x0 = NRHO_GUESS
    tr = propagate_stt(em, x0, 1.2)
    dx = 1e-4 * np.array([1, -2, 1, 3, -1, 2.0])
    truth = propagate(em, x0 + dx, 1.2).x[-1] - tr.x[-1]
    lin = tr.stm[-1] @ dx
    quad = lin + 0.5 * np.einsum("ijk,j,k->i", tr.stt[-1], dx, dx)
    assert np.linalg.norm(quad - truth) < 0.05 * np.linalg.norm(lin - truth)


def test_heyoka_matches_scipy_dop853_over_one_nrho_period(nrho):
    grid = np.linspace(0.0, nrho.period, 7)
    hy = propagate_stm(em, nrho.x0, grid)
    sp = propagate_scipy(em, nrho.x0, grid, stm=True, rtol=1e-13, atol=1e-14)
    assert np.max(np.abs(hy.x - sp.x)) < 1e-9
    assert np.max(np.abs(hy.stm - sp.stm)) / np.max(np.abs(sp.stm)) < 1e-7


def test_jacobi_constant_drift_over_ten_dro_periods():
    dro = orbits.correct_symmetric(em, [0.778008526, 0, 0, 0, 0.556190606, 0], fix="x0")
    t = np.linspace(0.0, 10 * dro.period, 401)
    C = em.jacobi(propagate(em, dro.x0, t).x)
    assert np.max(np.abs(C - C[0])) <= 1e-12


def test_batch_equals_single_and_backward_inverts_forward():
    rng = np.random.default_rng(3)
    X = NRHO_GUESS + 1e-3 * rng.standard_normal((7, 6))  # not a multiple of the SIMD batch size
    grid = np.linspace(0.0, 1.0, 5)
    batch = propagate_stm(em, X, grid)
    threaded = propagate_stm(em, X, grid, threads=2)
    assert batch.x.shape == (7, 5, 6) and batch.stm.shape == (7, 5, 6, 6)
    assert np.array_equal(batch.x, threaded.x)
    for i in (0, 6):
        one = propagate_stm(em, X[i], grid)
        assert np.max(np.abs(one.x - batch.x[i])) < 1e-13
        assert np.max(np.abs(one.stm - batch.stm[i])) < 1e-11
    back = propagate(em, batch.x[2, -1], grid[::-1])
    assert np.max(np.abs(back.x[-1] - X[2])) < 1e-11


def test_events_y_crossings_and_apses(nrho):
    ev = find_events(em, nrho.x0, nrho.period * (1 + 1e-9), ("y_crossing", "apse"))
    yc = ev.t[[k == "y_crossing" for k in ev.kind]]
    assert np.allclose(yc, [nrho.period / 2, nrho.period], rtol=0, atol=1e-10)
    peri = ev.x[[k == "periapsis" for k in ev.kind]]
    assert len(peri) == 1
    # at the apse the radial velocity w.r.t. the Moon vanishes
    r = peri[0, :3] - em.secondary_position
    assert abs(r @ peri[0, 3:]) < 1e-10
    assert abs(np.linalg.norm(r) * em.length_unit_km - nrho.perilune_radius_km) < 1e-6


@pytest.mark.parametrize(
    "kwargs, word",
    [
        (dict(x0=np.zeros(5), t=1.0), "x0"),
        (dict(x0=np.r_[np.nan, np.zeros(5)], t=1.0), "x0"),
        (dict(x0=NRHO_GUESS, t=[0.0, 1.0, 0.5]), "t"),
        (dict(x0=NRHO_GUESS, t=[0.0]), "t"),
        (dict(x0=NRHO_GUESS, t=1.0, tol=1.0), "tol"),
        (dict(x0=NRHO_GUESS, t=1.0, threads=0), "threads"),
    ],
)
def test_bad_arguments_raise(kwargs, word):
    with pytest.raises(ValueError, match=word):
        propagate_stm(em, **kwargs)


def test_collision_raises_instead_of_returning_junk():
    x0 = np.r_[em.secondary_position + [0.008, 0, 0], 0, 0, 0]  # released at rest 3075 km from the Moon's centre
    with pytest.raises(RuntimeError, match="impact on the Moon"):
        propagate(em, x0, 1.0)
    with pytest.raises(RuntimeError, match="impact on the Moon"):
        propagate_stm(em, np.vstack([x0, x0, x0, x0, x0]), [0.0, 1.0])  # batch path too
    # mathematically the fall continues through the singularity; impact=False lets a corrector explore it
    assert propagate(em, x0, 0.1, impact=False).x.shape == (2, 6)


def test_bad_event_kind():
    with pytest.raises(ValueError, match="events"):
        find_events(em, NRHO_GUESS, 1.0, ("perigee",))


# ---------------------------------------------------------------------------------------------------------------
# The arc impact check of the OCBE transitions (_check_arcs_outside_primaries): the fall-time bound and its screen
# ---------------------------------------------------------------------------------------------------------------


def _hermite(r0, r1, v0, v1, h, s):
    """Cubic Hermite interpolant of an interval at the fractions ``s`` (k,), written out independently."""
    s = np.asarray(s)[:, None]
    return ((1 + 2 * s) * (1 - s) ** 2 * r0 + s * (1 - s) ** 2 * h * v0 + s**2 * (3 - 2 * s) * r1
            + s**2 * (s - 1) * h * v1)


def _perilune(depth_km, speed_km_s, incl, body="Moon"):
    """A state at the closest approach ``depth_km`` below a primary's surface (above it if negative), speed
    ``speed_km_s`` perpendicular to the radius, tilted ``incl`` rad out of the x-y plane."""
    centre, radius_km = ((em.secondary_position, em.secondary_radius_km) if body == "Moon"
                         else (em.primary_position, em.primary_radius_km))
    r = em.km_to_lu(radius_km - depth_km)
    v = speed_km_s / em.velocity_unit_km_s
    return np.r_[centre + [r, 0, 0], 0, v * np.cos(incl), v * np.sin(incl)]


def _dipping_arcs(depth_km, speed_km_s, half_hours, n_sub, incl=0.3):
    """Arcs through a perilune ``depth_km`` below the lunar surface (above it if negative), sampled at ``n_sub`` (even)
    points outside the Moon, the perilune midway between two."""
    peri = _perilune(depth_km, speed_km_s, incl)
    h = float(em.days_to_tu(half_hours / 24.0))
    x0 = propagate(em, peri, np.array([0.0, -h]), impact=False).x[-1]
    t = np.linspace(0.0, 2 * h, n_sub)
    x = propagate(em, x0, t, impact=False).x
    assert np.all(np.linalg.norm(x[:, :3] - em.secondary_position, axis=-1) > em.secondary_radius)
    return t, x


def _bound(states, pieces):
    """The check's fall-time bound (TU) from each state, min over the two primaries (the check's own reduction)."""
    states = np.atleast_2d(states)
    C = em.jacobi(states)
    return np.minimum(*[pr._fall_time_bound(np.linalg.norm(states[:, :3] - body[1], axis=-1), C, *body[2:], pieces)
                        for body in pr._bodies(em)])


@pytest.fixture
def repropagations(monkeypatch):
    """The grid intervals the arc check re-propagates (its calls of ``_propagate_chunk``), in order."""
    calls = []
    chunk = pr._propagate_chunk
    monkeypatch.setattr(pr, "_propagate_chunk", lambda system, x0, grid, *a: calls.append(tuple(grid)) or
                        chunk(system, x0, grid, *a))
    return calls


def test_potential_bound_holds_on_every_shell_and_is_attained_up_to_the_rotation_term():
    # random points on shells about each primary (outside the other): the closed form is never below the
    # pseudo-potential; on the line towards the other primary the other two terms are exact, so the gap is the
    # rotation term's alone, ((offset + r)^2 - (offset - r)^2) / 2 = 2 offset r
    rng = np.random.default_rng(8)
    for name, centre, offset, radius, mass, other_mass, other_radius in pr._bodies(em):
        other = em.primary_position if name == "Moon" else em.secondary_position
        r = np.exp(rng.uniform(np.log(radius), np.log(0.95), 4000))
        u = rng.standard_normal((4000, 3))
        p = centre + r[:, None] * u / np.linalg.norm(u, axis=-1)[:, None]
        outside = np.linalg.norm(p - other, axis=-1) > other_radius
        bound = pr._potential_bound(r, r, offset, mass, other_mass, other_radius)
        assert np.all(bound[outside] >= em.pseudo_potential(p[outside]))
        r = np.linspace(radius, 1.0 - 1.01 * other_radius, 50)
        p = centre + r[:, None] * (other - centre) / np.linalg.norm(other - centre)
        gap = pr._potential_bound(r, r, offset, mass, other_mass, other_radius) - em.pseudo_potential(p)
        np.testing.assert_allclose(gap, 2 * offset * r, rtol=1e-9, atol=1e-12)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(["Moon", "Earth"]), st.floats(0.02, 0.6), st.floats(0.0, 1.0), st.floats(-1.5, 1.5),
       st.floats(0.05, 1.0), st.sampled_from([1, -1]))
def test_fall_time_bound_never_exceeds_the_true_time_to_impact(body, depth, speed, incl, before, sign):
    # ballistic arcs through a closest approach below a primary's surface (depth a fraction of the radius, speed
    # 0.95-1.3 times the escape speed there, so that the arc leaves the body): a sample taken ``before`` x (a
    # fraction of a day) ahead of the closest approach (sign 1) or after it (sign -1, time reversed), then the
    # impact that propagate's events find from that sample; the bound must not exceed the time from the sample to
    # the impact (it comes within 2 % of it on some of these arcs: 16 pieces, 200 random arcs)
    radius_km, gm = ((em.secondary_radius_km, em.mu) if body == "Moon" else (em.primary_radius_km, 1 - em.mu))
    v_esc = np.sqrt(2 * gm / em.km_to_lu(radius_km * (1 - depth))) * em.velocity_unit_km_s
    peri = _perilune(depth * radius_km, v_esc * (0.95 + 0.35 * speed), incl, body)
    tau = float(em.days_to_tu(before))
    sample = propagate(em, peri, np.array([0.0, -sign * tau]), impact=False).x[-1]
    r1, r2 = em.distances(sample)
    if r1 <= em.primary_radius * 1.001 or r2 <= em.secondary_radius * 1.001:
        return  # the sample is (almost) on a surface: nothing to bound
    try:
        propagate(em, sample, np.array([0.0, sign * 2 * tau]))
        raise AssertionError("the arc must hit: its closest approach lies below the surface")
    except pr.ImpactError as exc:
        fall = abs(exc.time)
    for pieces in (1, pr._FALL_PIECES):
        bound = _bound(sample, pieces)[0]
        assert bound <= fall, (pieces, bound, fall)


def test_arc_check_raises_on_a_long_interval_through_a_deep_fast_perilune():
    # the case the 17-point Hermite heuristic (before 2026-11-26d) missed: one 7.8-hour interval through a perilune
    # 584 km under the lunar surface at 2.76 km/s (propagate itself raises on it)
    t, x = _dipping_arcs(584.0, 2.76, 3.9, 2)
    with pytest.raises(pr.ImpactError, match="impact on the Moon"):
        propagate(em, x[0], t)
    s = np.linspace(0.0, 1.0, 17)
    p = _hermite(x[0, :3], x[1, :3], x[0, 3:], x[1, 3:], t[1] - t[0], s)
    reach = 0.5 * (t[1] - t[0]) * np.max(np.linalg.norm(x[:, 3:], axis=-1))
    assert np.min(np.linalg.norm(p - em.secondary_position, axis=-1)) > em.secondary_radius + reach  # missed
    nrho = orbits.nrho_9_2(em)
    calm = propagate(em, nrho.x0, nrho.period * np.array([0.4, 0.6])).x
    for screen in (True, False):
        with pytest.raises(pr.ImpactError, match="between grid points") as one:
            pr._check_arcs_outside_primaries(em, t, x, screen=screen)
        assert one.value.body == "Moon" and one.value.member is None
        with pytest.raises(pr.ImpactError, match="between grid points") as many:
            pr._check_arcs_outside_primaries(em, t, np.stack([calm, x], axis=1), first=4, screen=screen)
        assert many.value.member == 5 and many.value.time == one.value.time


@pytest.mark.parametrize("depth_km, speed_km_s, half_hours, n_sub", [
    (300.0, 2.5, 0.5, 2), (50.0, 2.5, 0.25, 2), (20.0, 3.0, 1.0, 4), (1000.0, 3.4, 2.0, 8)])
def test_arc_check_raises_on_arcs_that_dip_below_the_surface_between_samples(depth_km, speed_km_s, half_hours,
                                                                             n_sub):
    t, x = _dipping_arcs(depth_km, speed_km_s, half_hours, n_sub)
    nrho = orbits.nrho_9_2(em)
    calm = propagate(em, nrho.x0, nrho.period * np.linspace(0.4, 0.4 + 2 * (t[-1] - t[0]) / nrho.period, n_sub)).x
    batch = np.stack([calm, x, calm], axis=1)  # (n_sub, 3, 6): the middle arc dips
    for screen in (True, False):
        with pytest.raises(pr.ImpactError, match="between grid points") as one:
            pr._check_arcs_outside_primaries(em, t, x, screen=screen)
        assert one.value.body == "Moon" and one.value.member is None
        with pytest.raises(pr.ImpactError, match="between grid points") as many:
            pr._check_arcs_outside_primaries(em, t, batch, first=10, screen=screen)
        assert many.value.member == 11
        pr._check_arcs_outside_primaries(em, t, calm, screen=screen)  # an arc far from both primaries passes


def test_a_clear_nrho_period_on_the_detection_sub_grid_is_never_repropagated(repropagations):
    # one period of the 9:2 NRHO (perilune 3249 km from the Moon's centre) and 15 neighbours 4 km / 4 m/s off it,
    # on the detection study's 15-minute sub-grid, forward and backward: the bound clears every interval (the
    # perilune intervals by a factor of about 1.5 for the one-piece sum and 1.8 for the 16-piece one)
    nrho = orbits.nrho_9_2(em)
    rng = np.random.default_rng(5)
    X0 = np.vstack([nrho.x0, nrho.x0 + 1e-5 * rng.standard_normal((15, 6))])
    t = np.linspace(0.0, nrho.period, int(np.ceil(nrho.period / float(em.days_to_tu(15 / 1440)))) + 1)
    x = np.moveaxis(propagate(em, X0, t).x, 0, 1)  # (m, 16, 6)
    repropagations.clear()
    for screen in (True, False):
        pr._check_arcs_outside_primaries(em, t, x, screen=screen)
        pr._check_arcs_outside_primaries(em, t[::-1], x[::-1], screen=screen)
        pr._check_arcs_outside_primaries(em, t, x[:, 0], screen=screen)
    assert repropagations == []
    margin = (_bound(x[:-1, 0], pr._FALL_PIECES) + _bound(x[1:, 0], pr._FALL_PIECES)) / np.diff(t)
    assert 1.6 < margin.min() < 2.0  # cleared with a margin, and the bound is not loose near perilune


def test_screen_and_the_16_piece_sum_decide_alike_along_a_near_grazing_family(repropagations):
    # perilunes from 2000 km above to 400 km below the surface, on sub-grids of several spacings: the one-piece
    # screen never clears an interval that the 16-piece sum keeps, so both re-propagate the same intervals and
    # decide alike; every arc through a perilune below the surface raises, every other one passes
    rng = np.random.default_rng(2)
    for depth in np.linspace(-2000.0, 400.0, 12):
        for n_sub, half in ((2, 0.25), (4, 0.5), (8, 2.0), (2, 4.0)):
            t, x = _dipping_arcs(depth, rng.uniform(2.2, 3.5), half, n_sub, incl=rng.uniform(-1, 1))
            repropagations.clear()
            one = _bound(x[:-1], 1) + _bound(x[1:], 1)
            many = _bound(x[:-1], pr._FALL_PIECES) + _bound(x[1:], pr._FALL_PIECES)
            assert np.all(many >= one)
            outcomes, repropagated = [], []
            for screen in (True, False):
                repropagations.clear()
                try:
                    pr._check_arcs_outside_primaries(em, t, x, screen=screen)
                    outcomes.append("clear")
                except pr.ImpactError as exc:
                    outcomes.append(str(exc))
                repropagated.append(list(repropagations))
            assert outcomes[0] == outcomes[1], (depth, n_sub, outcomes)
            assert repropagated[0] == repropagated[1], (depth, n_sub)
            kept = [tuple(t[k:k + 2]) for k in np.flatnonzero(many <= np.diff(t))]
            assert repropagated[0] == kept[:len(repropagated[0])] and (depth < 0 or repropagated[0])
            assert (outcomes[0] == "clear") == (depth < 0), (depth, n_sub, outcomes)


@pytest.mark.parametrize("n", [5, 12, 13])
def test_wide_order_2_batches_give_the_narrow_batches_bits(n):
    """Order 2 is integrated in batches of twice heyoka's SIMD size (``_batch_plan``); every state's STM and STT are
    bit for bit those of the narrow batches (the path before 2026-11-26d) and belong to that state: a chunk plan
    that drops, repeats or shifts a state (a wrong lane order) fails."""
    rng = np.random.default_rng(n)
    x0 = np.array([7.80136159e-1, 0, 0, 0, 5.53104815e-1, 0]) + 1e-3 * rng.standard_normal((n, 6))
    grid = np.array([0.0, 0.3, 0.7])
    simd = 4
    plan = pr._batch_plan(n, simd, 2)
    assert [i for i, _ in plan] == sorted(i for i, _ in plan) and plan[0][0] == 0
    assert sum(min(b, n - i) for i, b in plan) == n and all(b in (simd, 2 * simd) for _, b in plan)
    assert any(b == 2 * simd for _, b in plan)
    assert pr._batch_plan(n, simd, 1) == [(i, simd) for i in range(0, n, simd)]  # orders 0 and 1 unchanged
    wide = propagate_stt(em, x0, grid)
    narrow = np.concatenate([pr._propagate_chunk(em, x0[i:i + simd], grid, 2, pr.DEFAULT_TOL, simd)
                             for i in range(0, n, simd)])
    _, stm_index, stt_index = pr._unpack_maps(2)
    assert np.array_equal(wide.x, narrow[..., :6])
    assert np.array_equal(wide.stm, narrow[..., stm_index]) and np.array_equal(wide.stt, narrow[..., stt_index])
    alone = propagate_stt(em, x0[n - 1], grid)  # the last (padded) lane is its own state's
    np.testing.assert_allclose(wide.stm[n - 1], alone.stm, rtol=0, atol=1e-12 * np.max(np.abs(alone.stm)))

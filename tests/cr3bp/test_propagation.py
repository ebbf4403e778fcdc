"""heyoka propagation: STM and STT against finite differences, against scipy, invariants, batch, events."""

import numpy as np
import pytest

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
# The arc impact check of the OCBE transitions (_check_arcs_outside_primaries) and its screen
# ---------------------------------------------------------------------------------------------------------------


def _hermite(r0, r1, v0, v1, h, s):
    """Cubic Hermite interpolant of an interval at the fractions ``s`` (k,), written out independently."""
    s = np.asarray(s)[:, None]
    return ((1 + 2 * s) * (1 - s) ** 2 * r0 + s * (1 - s) ** 2 * h * v0 + s**2 * (3 - 2 * s) * r1
            + s**2 * (s - 1) * h * v1)


def test_hermite_spread_bounds_the_interpolant_on_loops_and_random_arcs():
    rng = np.random.default_rng(11)
    s = np.linspace(0.0, 1.0, 2001)
    v = rng.standard_normal(3)
    cases = [(np.zeros(3), np.zeros(3), v, -v, 0.7),  # a closed loop: the bound is tight within 8/27 vs 1/4
             (np.zeros(3), np.zeros(3), v, v, 0.7),  # a figure of eight
             (np.zeros(3), 1e-3 * v, 3 * v, -2 * v, -0.4)]  # backward interval
    cases += [tuple(rng.standard_normal((4, 3)) * rng.choice([1e-3, 1.0, 10.0], 4)[:, None]) + (rng.uniform(-2, 2),)
              for _ in range(300)]
    worst = 0.0
    for r0, r1, v0, v1, h in cases:
        p = _hermite(r0, r1, v0, v1, h, s)
        bound = pr._hermite_spread(r0, r1, v0, v1, h)
        stray = max(np.max(np.linalg.norm(p - r0, axis=-1)), np.max(np.linalg.norm(p - r1, axis=-1)))
        worst = max(worst, stray / bound)
        assert stray <= bound * (1 + 1e-12), (r0, r1, v0, v1, h)
    assert worst > 0.8  # and not loose everywhere: the loop comes within 27/32 of it


def _dipping_arcs(depth_km, speed_km_s, half_hours, n_sub):
    """Arcs through a perilune ``depth_km`` below the lunar surface (above it if negative), sampled at ``n_sub`` (even)
    points outside the Moon, the perilune midway between two."""
    r = em.km_to_lu(em.secondary_radius_km - depth_km)
    v = speed_km_s / em.velocity_unit_km_s
    peri = np.array([1 - em.mu + r, 0, 0, 0, v * np.cos(0.3), v * np.sin(0.3)])
    h = float(em.days_to_tu(half_hours / 24.0))
    x0 = propagate(em, peri, np.array([0.0, -h]), impact=False).x[-1]
    t = np.linspace(0.0, 2 * h, n_sub)
    x = propagate(em, x0, t, impact=False).x
    assert np.all(np.linalg.norm(x[:, :3] - em.secondary_position, axis=-1) > em.secondary_radius)
    return t, x


@pytest.mark.parametrize("depth_km, speed_km_s, half_hours, n_sub", [
    (300.0, 2.5, 0.5, 2), (50.0, 2.5, 0.25, 2), (20.0, 3.0, 1.0, 4), (1000.0, 3.4, 2.0, 8)])
def test_screened_arc_check_raises_on_arcs_that_dip_below_the_surface_between_samples(depth_km, speed_km_s,
                                                                                       half_hours, n_sub):
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


def test_screen_keeps_every_interval_the_unscreened_test_flags_along_a_near_grazing_family(monkeypatch):
    # perilunes from 2000 km above to 400 km below the surface, on sub-grids of several spacings: the screen must
    # keep every interval the 17-point test would re-propagate (it may keep more), and both must re-propagate the
    # same intervals and decide alike
    calls = []
    chunk = pr._propagate_chunk
    monkeypatch.setattr(pr, "_propagate_chunk", lambda system, x0, grid, *a: calls.append(tuple(grid)) or
                        chunk(system, x0, grid, *a))
    rng = np.random.default_rng(2)
    s = np.linspace(0.0, 1.0, 17)
    for depth in np.linspace(-2000.0, 400.0, 12):
        for n_sub, half in ((2, 0.25), (4, 0.5), (8, 2.0)):
            t, x = _dipping_arcs(depth, rng.uniform(2.2, 3.5), half, n_sub)
            h = np.diff(t)
            r0, r1, v0, v1 = x[:-1, :3], x[1:, :3], x[:-1, 3:], x[1:, 3:]
            p = np.stack([_hermite(r0[k], r1[k], v0[k], v1[k], h[k], s) for k in range(n_sub - 1)])
            d = np.min(np.linalg.norm(p - em.secondary_position, axis=-1), axis=1)
            reach = 0.5 * h * np.maximum(np.linalg.norm(v0, axis=-1), np.linalg.norm(v1, axis=-1))
            flagged = d <= em.secondary_radius + reach
            clear = (np.maximum(np.linalg.norm(r0 - em.secondary_position, axis=-1),
                                np.linalg.norm(r1 - em.secondary_position, axis=-1))
                     - pr._hermite_spread(r0, r1, v0, v1, h))
            assert np.all(clear[flagged] <= em.secondary_radius + reach[flagged])
            outcomes, repropagated = [], []
            for screen in (True, False):
                calls.clear()
                try:
                    pr._check_arcs_outside_primaries(em, t, x, screen=screen)
                    outcomes.append("clear")
                except pr.ImpactError as exc:
                    outcomes.append(str(exc))
                repropagated.append(list(calls))
            assert outcomes[0] == outcomes[1], (depth, n_sub, outcomes)
            expected = [tuple(t[k:k + 2]) for k in np.flatnonzero(flagged)]  # up to the one that raises
            n_done = len(expected) if outcomes[0] == "clear" else max(1, len(repropagated[0]))
            assert repropagated[0] == repropagated[1] == expected[:n_done], (depth, n_sub)
            assert (outcomes[0] == "clear") == (depth < 0), (depth, n_sub, outcomes)

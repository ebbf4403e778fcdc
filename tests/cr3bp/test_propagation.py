"""heyoka propagation: STM and STT against finite differences, against scipy, invariants, batch, events."""

import numpy as np
import pytest

from cislunar.cr3bp import orbits
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

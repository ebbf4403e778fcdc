"""SCvx with first-order hold: convergence, feasibility, independence from the guess, homotopy monotonicity."""

import numpy as np
import pytest

from cislunar import discretization as D
from cislunar import reference, scvx
from cislunar.dynamics import EARTH_MOON as em
from cislunar.propagation import propagate

A_MAX = 1e-6 / em.acceleration_unit_km_s2  # 1e-6 km/s^2 (Wolf & Jones Table 3)


@pytest.fixture(scope="module")
def transfer():
    """Wolf & Jones test case 1 boundary conditions: corrected observer DRO -> x_S(tf) DRO state, two periods."""
    rows = {r.label: r for r in reference.load_wolf_jones_table() if r.table == 2}
    dro = reference.verify_table_row(em, rows["observer_t0"]).corrected
    xf = np.array([rows["observer_tf"].x0, 0, 0, 0, rows["observer_tf"].vy0, 0])
    t = np.linspace(0.0, 2 * dro.period, 30)
    return dro, xf, t


def test_minimum_impulse_transfer_converges_to_a_feasible_trajectory(transfer):
    dro, xf, t = transfer
    res = scvx.solve_scvx(em, t, propagate(em, dro.x0, t).x, np.zeros((t.size, 3)), np.full(t.size, A_MAX),
                          x_final=xf)
    assert res.max_defect < 1e-10
    assert np.all(np.linalg.norm(res.u, axis=1) <= A_MAX * (1 + 1e-7))
    # the nonlinear flow under the FOH control, from the initial state alone, lands on the terminal state
    xs = D.propagate_foh(em, dro.x0, t, res.u)
    assert np.max(np.abs(xs[-1] - xf)) < 1e-9
    accepted = [h for h in res.history if h["accepted"]]
    assert all(b["cost"] <= a["cost"] + 1e-12 for a, b in zip(accepted, accepted[1:]))  # monotone on accepted steps
    # a different initial guess (random controls, a blended state path) reaches the same optimum
    rng = np.random.default_rng(1)
    back = propagate(em, xf, t[::-1]).x[::-1]
    s = (t / t[-1])[:, None]
    guess = (1 - s) * propagate(em, dro.x0, t).x + s * back
    res2 = scvx.solve_scvx(em, t, guess, 0.1 * A_MAX * rng.standard_normal((t.size, 3)), np.full(t.size, A_MAX),
                           x_final=xf)
    assert abs(res2.impulse - res.impulse) < 1e-5 * res.impulse
    assert np.max(np.abs(res2.u - res.u)) < 1e-3 * A_MAX


def test_no_terminal_constraint_and_no_information_means_no_thrust(transfer):
    dro, _, t = transfer
    res = scvx.solve_scvx(em, t, propagate(em, dro.x0, t).x, np.zeros((t.size, 3)), np.full(t.size, A_MAX))
    assert res.impulse < 1e-10


def test_homotopy_trades_impulse_for_information(transfer):
    dro, xf, t = transfer
    k_star = 10
    direction = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # a linear "information" rewarding +x at node k_star

    def info(x):
        return 5.0 * direction @ x[k_star], 5.0 * direction, k_star

    out = []
    for alpha in (0.0, 0.01, 0.05):
        res = scvx.solve_scvx(em, t, propagate(em, dro.x0, t).x, np.zeros((t.size, 3)), np.full(t.size, A_MAX),
                              x_final=xf, info=info, alpha=alpha)
        out.append((res.impulse, info(res.x)[0]))
        assert res.max_defect < 1e-10
    impulses, infos = zip(*out)
    assert impulses[0] < impulses[1] < impulses[2]
    assert infos[0] < infos[1] < infos[2]


def test_bad_arguments(transfer):
    dro, xf, t = transfer
    x = propagate(em, dro.x0, t).x
    with pytest.raises(ValueError, match="alpha"):
        scvx.solve_scvx(em, t, x, np.zeros((t.size, 3)), np.full(t.size, A_MAX), alpha=1.5)
    with pytest.raises(ValueError, match="u_max"):
        scvx.solve_scvx(em, t, x, np.zeros((t.size, 3)), -np.ones(t.size))
    with pytest.raises(ValueError, match="rho0"):
        scvx.SCvxSettings(rho0=0.5, rho1=0.2)
    with pytest.raises(scvx.SCvxError, match="infeasible|collapsed|no convergence"):
        # a terminal state out of reach with no thrust at all
        scvx.solve_scvx(em, t, x, np.zeros((t.size, 3)), np.zeros(t.size), x_final=xf,
                        settings=scvx.SCvxSettings(max_iter=5))

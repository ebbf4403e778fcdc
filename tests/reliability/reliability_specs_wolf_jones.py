"""Malformed-argument specs for :mod:`cislunar.papers.wolf_jones.scenarios` (plugin of tests/test_reliability.py, issue 11).

One :class:`Spec` per public function and per public method of the scenario, information, keep-out and solver
classes, each with a cheap valid baseline call.  Calls that would run SCvx use a deterministic stand-in solver
(the argument checks come before any solve), so the sweep costs seconds.
"""

from __future__ import annotations

import functools

import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.wolf_jones import scenarios as W

MODULES = [W]
EXEMPT: dict = {}


@functools.lru_cache(maxsize=None)
def case1():
    return W.test_case_1()


@functools.lru_cache(maxsize=None)
def nodes():
    return case1().node_times(6)


@functools.lru_cache(maxsize=None)
def info_model():
    return case1().information_model()


@functools.lru_cache(maxsize=None)
def keep_out():
    return case1().keep_out(nodes()[1])


@functools.lru_cache(maxsize=None)
def window_start():
    from cislunar.cr3bp.propagation import propagate

    sc = case1()
    return propagate(sc.system, sc.observer_x0, [0.0, sc.window[0]]).x[-1]


class _Result:
    """What a solver returns, as far as the sweep and the impulse search look at it."""

    def __init__(self, alpha, x, u):
        self.alpha, self.x, self.u = float(alpha), np.asarray(x), np.asarray(u)
        self.impulse = 10.0 * self.alpha
        self.cost = -self.alpha
        self.iterations = 1


def fake_solver(alpha, x_guess, u_guess):
    """Deterministic stand-in for :class:`cislunar.papers.wolf_jones.scenarios.ScenarioSolver`: impulse = 10 alpha_h."""
    return _Result(alpha, x_guess, u_guess)


def specs(Spec, lazy):
    s = []
    S = Spec
    X = np.array([0.8, 0.0, 0.0, 0.0, 0.52, 0.0])
    T = np.array([0.0, 0.5, 1.0, 1.5])
    U = np.zeros((4, 3))
    # module functions
    s.append(S("keep_out_radius_km", W.keep_out_radius_km, dict(sigma_pos_km=100.0, n_sigma=3.0),
               dict(sigma_pos_km="pos", n_sigma="pos")))
    # impulse is cislunar.guidance.scvx.impulse re-exported (its spec is in reliability_specs_estimation.py)
    s.append(S("node_times_with_window", W.node_times_with_window,
               dict(t_nodes=np.linspace(0.0, 10.0, 8), window=np.array([2.0, 5.0])),
               dict(t_nodes="grid", window="arr")))
    for name in ("test_case_1", "test_case_2"):
        s.append(S(name, getattr(W, name), dict(system=em, q=W.PROCESS_NOISE_PSD_ND, a_max_km_s2=1e-6),
                   dict(system="system", q="nonneg", a_max_km_s2="nonneg")))
    s.append(S("evaluate_crlb", W.evaluate_crlb, dict(scenario=lazy(case1), x_window_start=lazy(window_start),
                                                      q=None),
               dict(scenario="instance", x_window_start="state", q="nonneg_opt")))
    s.append(S("fly", W.fly, dict(scenario=lazy(case1), t_nodes=T, u_nodes=U, refine=2),
               dict(scenario="instance", t_nodes="grid", u_nodes="arr", refine="int1")))
    s.append(S("terminal_miss_km", W.terminal_miss_km, dict(scenario=lazy(case1), t_nodes=T, u_nodes=U),
               dict(scenario="instance", t_nodes="grid", u_nodes="arr")))
    s.append(S("sweep_both_ways", W.sweep_both_ways,
               dict(solver=fake_solver, alphas=np.array([0.0, 0.01]), x_guess=np.zeros((4, 6)), u_guess=U,
                    executor=None, directions=("up", "down")),
               dict(solver="callable", alphas="vec", x_guess="arr", u_guess="arr", executor="instance_opt",
                    directions="directions")))
    s.append(S("solve_for_impulse", W.solve_for_impulse,
               dict(solver=fake_solver, budget=0.05, lower=(0.0, fake_solver(0.0, X, U[:1])),
                    upper=(0.01, fake_solver(0.01, X, U[:1])), rtol=0.02, max_solves=3),
               dict(solver="callable", budget="pos", lower="instance", upper="instance", rtol="range:0:1",
                    max_solves="int1")))
    # Scenario methods
    sc = lazy(case1)
    for meth, kw, kinds in (
            ("node_times", dict(n_nodes=6, sigma=1.0), dict(n_nodes="int1", sigma="real")),
            ("control_bounds", dict(t_nodes=T), dict(t_nodes="grid")),
            ("ballistic_guess", dict(t_nodes=T), dict(t_nodes="grid")),
            ("seeded_guess", dict(t_nodes=T, z_sign=1.0, fraction=0.05),
             dict(t_nodes="grid", z_sign="real", fraction="range:0:1")),
            ("targets_at", dict(t=np.array([1.0, 2.0])), dict(t="arr_finite")),
            ("information_model", dict(x_reference=lazy(window_start), q=None),
             dict(x_reference="state_opt", q="nonneg_opt")),
            ("keep_out", dict(node=3, d_min_km=None), dict(node="int0", d_min_km="pos_opt"))):
        s.append(S(f"Scenario.{meth}", lazy(lambda m=meth: getattr(case1(), m)), kw, kinds))
    del sc
    # WindowInformation
    m = info_model
    s.append(S("WindowInformation", W.WindowInformation,
               dict(system=em, t=lazy(lambda: m().t), targets_x0=lazy(lambda: m().targets_x0),
                    model=lazy(lambda: m().model), noise=lazy(lambda: m().noise), P0=lazy(lambda: m().P0),
                    q=1e-11, x_reference=lazy(window_start), hessian_step=1e-6, hessian_scheme="central"),
               dict(system="system", t="grid", targets_x0="arr", model="instance", noise="spd", P0="spd",
                    q="nonneg", x_reference="state", hessian_step="pos", hessian_scheme="choice")))
    for meth, kw, kinds in (("__call__", dict(x=lazy(window_start), order=0), dict(x="state", order="int0")),
                            ("hessian", dict(x=lazy(window_start)), dict(x="state")),
                            ("concave_model", dict(x=lazy(window_start)), dict(x="state")),
                            ("linearization", dict(x=lazy(window_start), derivatives=False),
                             dict(x="state", derivatives="bool"))):
        s.append(S(f"WindowInformation.{meth}", lazy(lambda mm=meth: getattr(info_model(), mm)), kw, kinds))
    # MinimumRange
    s.append(S("MinimumRange", W.MinimumRange,
               dict(system=em, t=lazy(lambda: case1().measurement_times), targets_x0=lazy(lambda: case1().targets_x0),
                    d_min=em.km_to_lu(424.0), node=3),
               dict(system="system", t="grid", targets_x0="arr", d_min="pos", node="int0")))
    for meth in ("ranges", "__call__"):
        s.append(S(f"MinimumRange.{meth}", lazy(lambda mm=meth: getattr(keep_out(), mm)), dict(x=lazy(window_start)),
                   dict(x="state")))
    # ScenarioSolver (construction only: a call runs SCvx, whose arguments are swept by the scvx plugin)
    s.append(S("ScenarioSolver", W.ScenarioSolver,
               dict(scenario=lazy(case1), t_nodes=lazy(lambda: nodes()[0]), k_window=lazy(lambda: nodes()[1]),
                    information=lazy(info_model), keep_out=True, d_min_km=424.0, settings=None),
               dict(scenario="instance", t_nodes="grid", k_window="int1", information="callable_opt",
                    keep_out="bool", d_min_km="pos_opt", settings="instance_opt")))
    return s

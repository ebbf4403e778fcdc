"""Malformed-argument specs (issue 18) for the Nychka & Bhattacharya package: studies, exercises, readouts, figures.

Loaded by ``tests/reliability/test_reliability.py`` (plugin protocol: ``MODULES``, ``EXEMPT``, ``specs(Spec, lazy)``).
Every public function of the package's non-claims modules, and every public method of its result objects that takes
an argument, gets one cheap valid call and the kind of each argument.  ``paper_scenario``, ``sensitivity_study`` and
the two :class:`SensitivityStudy` methods are swept by ``reliability_specs_estimation.py`` (not repeated here).

Cheap valid objects: the 2:1 orbit sampled at 50 points, its scheduling box narrowed to the three parameters the
theta1 LMIs depend on (8 vertices instead of 64: the six-sensor designs solve in seconds), a Fig. 3 run of seven
samples, and a hand-built one-orbit :class:`SensitivityStudy`.  The robust chapter (``robust``, notebook 12
section 6) uses a two-draw scheduling-error run whose widened box is narrowed the same way (8 vertices), robust
designs with one bisection step and one verification sample (about 1 s), and a 0.05-period window at the 233-min
interval (9 samples).  Each is built once (``functools.lru_cache``).

``fig1_scene``'s ``rso`` (a ``(p, q, perigee radius)`` tuple) is swept as an "iterable" (None, 3.0, object(),
"abc"); its item checks (a 2-tuple, ``(3.5, 1, 0.3)``, p <= q, a perigee radius out of range) are tested in
``tests/papers/nychka_bhattacharya/test_robust.py``.

Labels are ``<function>.nb_<module>`` (the sweep matches a function by the part before the first dot): the package
has two functions of the same name in different modules (``trade_curve``, ``allowances``, ``bandwidth``,
``line_crossings``), and other plugins may use the plain names.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
from spec_helpers import closed as _closed

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import lpv
from cislunar.papers.nychka_bhattacharya import exercises as ex
from cislunar.papers.nychka_bhattacharya import figures as fg
from cislunar.papers.nychka_bhattacharya import observer_simulation as obs
from cislunar.papers.nychka_bhattacharya import readout as ro
from cislunar.papers.nychka_bhattacharya import robust as rb
from cislunar.papers.nychka_bhattacharya import scenarios as nb_scenarios
from cislunar.papers.nychka_bhattacharya import sensing_precision as sp

MODULES = [nb_scenarios, sp, obs, ex, ro, fg, rb]
EXEMPT: dict = {}


# ----------------------------------------------------------------------------------------- cached valid objects
@functools.lru_cache(maxsize=None)
def _scenario():
    """The 2:1 orbit with its box narrowed to rho1..rho3 (the others held at the centre): 8 LMI vertices."""
    sc = nb_scenarios.paper_scenario(em, n_samples=50)
    lo, hi, c = sc.box.lower.copy(), sc.box.upper.copy(), sc.box.centre
    lo[3:], hi[3:] = c[3:], c[3:]
    return dataclasses.replace(sc, box=lpv.ParameterBox(lo, hi, source="reliability sweep: 8 vertices"))


@functools.lru_cache(maxsize=None)
def _designs():
    return sp.paper_designs(_scenario())


@functools.lru_cache(maxsize=None)
def _exactness():
    return sp.exactness_checks(lpv.CR3BPLPV(em), 5, np.random.default_rng(0))


@functools.lru_cache(maxsize=None)
def _checks():
    return sp.solver_independence(_scenario(), _designs())


@functools.lru_cache(maxsize=None)
def _bandwidth():
    return sp.bandwidth_study(_scenario(), [1000.0])


@functools.lru_cache(maxsize=None)
def _verification():
    return sp.verify_designs(_scenario(), _designs(), 1, np.random.default_rng(0))


@functools.lru_cache(maxsize=None)
def _objective():
    return sp.objective_norm_study(_scenario(), _designs())


@functools.lru_cache(maxsize=None)
def _allowances():
    return sp.allowances(_designs())


@functools.lru_cache(maxsize=None)
def _trade():
    return sp.trade_curve(_designs(), [0.0013, 0.002])


def _study():
    """A one-orbit, one-structure, one-level study (the numbers of a real one, no solve)."""
    one = np.ones((1, 1, 1))
    st = np.full((1, 1, 1), "optimal")
    return sp.SensitivityStudy(orbits=((2, 1, 0.3),), r13_max=np.array([0.98]), period=np.array([6.2]),
                               structures=("acceleration",), levels=np.array([1e-3]), gamma=0.0013,
                               pole_radius=1000.0, h2_kappa=one * 2800.0, hinf_kappa=one * 750.0, h2_status=st,
                               hinf_status=st, h2_gain=one, hinf_gain=one, seconds=0.0)


@functools.lru_cache(maxsize=None)
def _reading():
    return sp.read_sensitivity(_study())


@functools.lru_cache(maxsize=None)
def _od():
    return obs.observer_designs(_scenario(), 1, np.random.default_rng(0))


@functools.lru_cache(maxsize=None)
def _sim():
    return obs.simulate_fig3(_scenario(), _od(), 0.05, 0.05, 0.1, np.random.default_rng(1))


@functools.lru_cache(maxsize=None)
def _conv():
    return obs.convergence_study(_scenario(), _od(), _sim(), 0.1, e0_scales=(1.0,))


@functools.lru_cache(maxsize=None)
def _crossings():
    return obs.line_crossings(_sim(), 0.1)


@functools.lru_cache(maxsize=None)
def _rerun():
    return obs.window_rerun(_scenario(), _od(), _sim(), 0.05, 0.05, 0.1, np.random.default_rng(2))


@functools.lru_cache(maxsize=None)
def _allowance_at():
    return obs.allowance_at(_od(), 0.05)


DT_233 = 0.0373  # TU: the interval at which the H2 design allows 0.1 deg per sample (notebook 12, section 6)


def _narrowed(box, source):
    """``box`` with rho4..rho6 held at its centre (8 vertices, as :func:`_scenario`)."""
    lo, hi = box.lower.copy(), box.upper.copy()
    c = 0.5 * (lo + hi)
    lo[3:], hi[3:] = c[3:], c[3:]
    return lpv.ParameterBox(lo, hi, source=source)


@functools.lru_cache(maxsize=None)
def _serr():
    """Two noise draws per orbit sample; the widened box narrowed to 8 vertices (the robust LMIs solve in ~0.1 s)."""
    se = rb.scheduling_error(_scenario(), 0.1, 2, np.random.default_rng(0))
    return dataclasses.replace(se, box=_narrowed(se.box, "reliability sweep: widened box, 8 vertices"))


@functools.lru_cache(maxsize=None)
def _robust():
    return rb.robust_designs(_scenario(), _serr(), DT_233, 1, np.random.default_rng(0), iters=1)


@functools.lru_cache(maxsize=None)
def _window():
    return rb.simulate_window(_scenario(), _od(), _robust(), 0.05, np.random.default_rng(0))


@functools.lru_cache(maxsize=None)
def _scene():
    return nb_scenarios.fig1_scene(_scenario(), 2, n_samples=10)




def specs(Spec, lazy):
    S = Spec
    s = []
    rng = lazy(lambda: np.random.default_rng(0))
    sc, D = lazy(_scenario), lazy(_designs)
    od, sim = lazy(_od), lazy(_sim)

    def add(module, name, kwargs, kinds, **kw):
        s.append(S(f"{name}.nb_{module.__name__.rsplit('.', 1)[-1]}", getattr(module, name), kwargs, kinds, **kw))

    def method(label, bound, kwargs, kinds):
        s.append(S(f"{label}.nb", lazy(bound), kwargs, kinds))

    # ------------------------------------------------------------------------------ sensing_precision (nb 11)
    add(sp, "exactness_checks", dict(model=lpv.CR3BPLPV(em), n_states=3, rng=rng),
        dict(model="instance", n_states="int1", rng="rng"))
    add(sp, "paper_designs", dict(scenario=sc, gamma=0.0013, pole_radius=1000.0),
        dict(scenario="instance", gamma="pos", pole_radius="pos"))
    add(sp, "solver_independence", dict(scenario=sc, designs=D), dict(scenario="instance", designs="instance"))
    add(sp, "bandwidth_study", dict(scenario=sc, radii=np.array([1000.0]), gamma=0.0013),
        dict(scenario="instance", radii="vec", gamma="pos"))
    add(sp, "verify_designs", dict(scenario=sc, designs=D, n_samples=1, rng=rng),
        dict(scenario="instance", designs="instance", n_samples="int1", rng="rng"))
    add(sp, "objective_norm_study", dict(scenario=sc, designs=D, sparsity_tol=1e-4, same_tol=1e-3),
        dict(scenario="instance", designs="instance", sparsity_tol="range:0:1", same_tol="pos"))
    add(sp, "allowances", dict(designs=D, system=em), dict(designs="instance", system="system"))
    add(sp, "trade_curve", dict(designs=D, gammas=np.array([0.0013, 0.002])), dict(designs="instance", gammas="vec"))
    add(sp, "read_sensitivity", dict(study=_study(), reference_level=1e-3, system=em),
        dict(study="instance", reference_level="nonneg", system="system"))
    for name in ("same_theta1", "all_used"):
        method(f"ObjectiveStudy.{name}", lambda n=name: getattr(_objective(), n), dict(objective="l1"),
               dict(objective="choice"))

    # ---------------------------------------------------------------------------- observer_simulation (nb 12)
    add(obs, "observer_designs", dict(scenario=sc, n_verify=1, rng=rng, gamma=0.0013, pole_radius=1000.0),
        dict(scenario="instance", n_verify="int1", rng="rng", gamma="pos", pole_radius="pos"))
    add(obs, "allowance_at", dict(designs=od, dt=0.05), dict(designs="instance", dt="pos"))
    add(obs, "simulate_fig3",
        dict(scenario=sc, designs=od, dt=0.05, periods=0.05, sigma_deg=0.1, rng=rng, sigma_acc=1e-3, p0_sigma=0.03,
             initial_error=obs.INITIAL_ERROR),
        dict(scenario="instance", designs="instance", dt="pos", periods="pos", sigma_deg="nonneg", rng="rng",
             sigma_acc="nonneg", p0_sigma="pos", initial_error="arr"))
    t11 = np.linspace(0.0, 1.0, 11)
    add(obs, "first_and_rms", dict(t=t11, position_error=np.linspace(5.0, 0.5, 11), bound=1.0, period=10.0),
        dict(t="vec", position_error="arr", bound="nonneg", period="pos"))
    add(obs, "convergence_study",
        dict(scenario=sc, designs=od, sim=sim, sigma_deg=0.1, e0_scales=np.array([1.0]), seed=0, executor=None),
        dict(scenario="instance", designs="instance", sim="instance", sigma_deg="nonneg", e0_scales="vec",
             seed="seed", executor="instance_opt"))
    add(obs, "line_crossings", dict(sim=sim, window=0.1), dict(sim="instance", window="pos"))
    add(obs, "window_rerun", dict(scenario=sc, designs=od, sim=sim, dt=0.05, periods=0.05, sigma_deg=0.1, rng=rng),
        dict(scenario="instance", designs="instance", sim="instance", dt="pos", periods="pos", sigma_deg="nonneg",
             rng="rng"))
    method("Fig3Runs.median_settled", lambda: _sim().median_settled, dict(name="h2"), dict(name="choice"))
    method("Convergence.converges", lambda: _conv().converges, dict(name="h2", period=6.0),
           dict(name="choice", period="pos"))
    method("Convergence.stays", lambda: _conv().stays, dict(name="h2"), dict(name="choice"))
    method("Convergence.e0_max_ok", lambda: _conv().e0_max_ok, dict(initial_error=1e4, period=6.0),
           dict(initial_error="nonneg", period="pos"))

    # ------------------------------------------------------------------------ robust (nb 12, section 6)
    model = lpv.CR3BPLPV(em)
    states = np.array([[-0.3, 0.05, 0.0, -1.5], [-0.25, 0.1, 0.2, -1.6]])
    # states: any (..., 4) stack is valid (rho_hat's shape follows it), so only its type and finiteness are swept
    add(rb, "parameter_errors", dict(model=model, states=states, rho_hat=model.rho(states) * 1.01),
        dict(model="instance", states="arr_finite", rho_hat="arr"))
    add(rb, "scheduling_error",
        dict(scenario=sc, sigma_deg=0.1, n_draws=2, rng=rng, coverage=0.999, sin3_threshold=0.04),
        dict(scenario="instance", sigma_deg="pos", n_draws="int1", rng="rng", coverage="range:0.5:1",
             sin3_threshold="range:0:1"))
    add(rb, "robust_designs",
        dict(scenario=sc, serr=lazy(_serr), dt=DT_233, n_verify=1, rng=rng, pole_radius=1000.0, iters=1),
        dict(scenario="instance", serr="instance", dt="pos", n_verify="int1", rng="rng", pole_radius="pos",
             iters="int1"))
    add(rb, "simulate_window",
        dict(scenario=sc, nominal=od, robust=lazy(_robust), periods=0.05, rng=rng, small_scale=rb.SMALL_E0_SCALE),
        dict(scenario="instance", nominal="instance", robust="instance", periods="pos", rng="rng",
             small_scale="pos"))
    for name in ("rms", "holds", "fix_following"):
        method(f"WindowStudy.{name}", lambda n=name: getattr(_window(), n),
               dict(design="robust", norm="h2", start="large"), dict(design="choice", norm="choice", start="choice"))
    method("WindowStudy.fix_residual", lambda: _window().fix_residual,
           dict(design="robust", norm="hinf", start="large", lag=1),
           dict(design="choice", norm="choice", start="choice", lag="int0"))

    # -------------------------------------------------------------------------------------- scenarios (Fig. 1)
    add(nb_scenarios, "fig1_scene", dict(scenario=sc, n_platforms=2, rso=(3, 1, 0.3), rso_phase=0.3, n_samples=10),
        dict(scenario="instance", n_platforms="int1", rso="iterable", rso_phase="range:0:1", n_samples="int2"))

    # -------------------------------------------------------------------------------------------- exercises
    small = dict(n_samples=10)
    add(ex, "exercise_11_gamma", dict(factor=2.0, gamma=0.0013, pole_radius=1000.0, **small),
        dict(factor="pos", gamma="pos", n_samples="int2", pole_radius="pos"))
    add(ex, "exercise_11_orbit", dict(orbit=(3, 1, 0.3), gamma=0.0013, pole_radius=1000.0, **small),
        dict(orbit="iterable", gamma="pos", n_samples="int2", pole_radius="pos"))
    add(ex, "exercise_11_bandwidth", dict(pole_radius=200.0, gamma=0.0013, **small),
        dict(pole_radius="pos", gamma="pos", n_samples="int2"))
    short = dict(dt=0.05, periods=0.05, **small)
    add(ex, "exercise_12_noise", dict(factor=2.0, sigma_deg=0.1, seed=0, **short),
        dict(factor="pos", sigma_deg="pos", dt="pos", periods="pos", n_samples="int2", seed="seed"))
    add(ex, "exercise_12_initial_error", dict(scale=0.1, **short),
        dict(scale="range:0:1", dt="pos", periods="pos", n_samples="int2"))
    add(ex, "exercise_12_interval", dict(factor=0.5, dt=0.004, n_verify=1, seed=0, **small),
        dict(factor="pos", dt="pos", n_samples="int2", n_verify="int1", seed="seed"))

    # ---------------------------------------------------------------------------------------------- readout
    I = "instance"  # noqa: E741
    exact, study, rd = lazy(_exactness), _study(), lazy(_reading)
    add(ro, "dynamics", dict(ex=exact), dict(ex=I))
    add(ro, "sensors", dict(ex=exact), dict(ex=I))
    add(ro, "scenario", dict(sc=sc), dict(sc=I))
    add(ro, "disturbance", dict(system=em), dict(system="system"))
    add(ro, "designs", dict(D=D), dict(D=I))
    add(ro, "solver_checks", dict(checks=lazy(_checks)), dict(checks=I))
    add(ro, "bandwidth", dict(bw=lazy(_bandwidth)), dict(bw=I))
    add(ro, "verification", dict(ver=lazy(_verification), gamma=0.0013), dict(ver=I, gamma="pos"))
    add(ro, "objective", dict(obj=lazy(_objective), D=D), dict(obj=I, D=I))
    add(ro, "allowances", dict(al=lazy(_allowances), D=D, bw=lazy(_bandwidth), orbit="2:1"),
        dict(al=I, D=I, bw=I, orbit="instance_str"))
    add(ro, "trade_curve", dict(tc=lazy(_trade), system=em), dict(tc=I, system="system"))
    add(ro, "study_table", dict(study=study, rd=rd), dict(study=I, rd=I))
    add(ro, "study_verdict", dict(study=study, rd=rd), dict(study=I, rd=I))
    add(ro, "observer_gains", dict(od=od, gamma=0.0013), dict(od=I, gamma="pos"))
    add(ro, "allowance_at_dt", dict(al=lazy(_allowance_at), sigma_deg=0.1, system=em),
        dict(al=I, sigma_deg="pos", system="system"))
    add(ro, "measurements", dict(sim=sim, sc=sc), dict(sim=I, sc=I))
    for name in ("convergence", "convergence_time", "converges"):
        add(ro, name, dict(cv=lazy(_conv), sim=sim, system=em), dict(cv=I, sim=I, system="system"))
    add(ro, "line_crossings", dict(lc=lazy(_crossings), sim=sim, system=em), dict(lc=I, sim=I, system="system"))
    add(ro, "comparison", dict(sim=sim, ww=lazy(_rerun), od=od, al=lazy(_allowance_at), sigma_deg=0.1, system=em),
        dict(sim=I, ww=I, od=I, al=I, sigma_deg="pos", system="system"))
    add(ro, "scheduling_error", dict(se=lazy(_serr), system=em), dict(se=I, system="system"))
    add(ro, "robust_designs", dict(rd=lazy(_robust), system=em), dict(rd=I, system="system"))
    add(ro, "window", dict(ws=lazy(_window), rd=lazy(_robust), od=od, system=em),
        dict(ws=I, rd=I, od=I, system="system"))
    method("Readout.judged", lambda: ro.Readout("").judged, dict(claims={}), dict(claims=I))

    # ---------------------------------------------------------------------------------------------- figures
    add(fg, "resonant_orbit", dict(scenario=sc), dict(scenario=I))
    add(fg, "bandwidth", dict(bw=lazy(_bandwidth)), dict(bw=I))
    add(fg, "precision_per_sensor", dict(designs=D), dict(designs=I))
    add(fg, "trade_curve", dict(tc=lazy(_trade), gamma=0.0013, length_unit_km=em.length_unit_km),
        dict(tc=I, gamma="pos", length_unit_km="pos"))
    add(fg, "sensitivity", dict(study=study, reading=rd, gamma=0.0013, pole_radius=1000.0),
        dict(study=I, reading=I, gamma="pos", pole_radius="pos"))
    add(fg, "fig3_observers", dict(sim=sim, conv=lazy(_conv), crossings=lazy(_crossings), system=em, gamma=0.0013,
                                   sigma_deg=0.1),
        dict(sim=I, conv=I, crossings=I, system="system", gamma="pos", sigma_deg="nonneg"))
    for name, kwargs, kinds in (("fig1_analogue", dict(scene=lazy(_scene), system=em), dict(scene=I, system="system")),
                                ("fig3_window", dict(ws=lazy(_window), system=em), dict(ws=I, system="system"))):
        s.append(S(f"{name}.nb_figures", _closed(getattr(fg, name)), kwargs, kinds))
    return s

r"""Worked solutions of the exercises that close the Wolf & Jones chapters (notebooks 02-06), and of notebook 01's
exercise on Wolf & Jones' DRO tables (``MU_STEP``; the chapter's other exercises are Greaves & Scheeres').

Each notebook ends with a markdown cell "Exercises": change a parameter, predict what happens, then check.  The
functions here are the worked solutions, at sizes small enough to run in a few seconds; each returns a small frozen
dataclass with the numbers that answer the exercise and a one-paragraph ``answer``.  The function names carry the
notebook number (``exercise_02_...`` answers an exercise of notebook 02).

Units: as in the studies they call (non-dimensional LU, TU in the CR3BP, Earth-Moon rotating frame) unless a field
name says ``_km``, ``_mps`` or ``_km_s2``; information in nats.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON, check_system
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import _checks, nodes_study, scenarios, scvx_study
from cislunar.papers.wolf_jones import mutual_information_study as mi_study
from cislunar.papers.wolf_jones import reference_tables as wjt  # notebook 01
from cislunar.papers.wolf_jones import test_case_studies as tc_studies  # notebooks 05-06
from cislunar.sensing import information as info
from cislunar.sensing import measurements as meas
from cislunar.utils import validation

__all__ = [
    "ControlSizeAnswer",
    "MonteCarloSamplesAnswer",
    "MuStepAnswer",
    "NodeCountAnswer",
    "NodeSpacingAnswer",
    "RangeNoiseAnswer",
    "ThrustBoundAnswer",
    "exercise_01_mu_step",
    "exercise_02_monte_carlo_samples",
    "exercise_02_range_noise",
    "exercise_03_node_count",
    "exercise_03_thrust_bound",
    "exercise_04_control_size",
    "exercise_04_node_count",
]


# ===============================================================================================================
# Notebook 01: how tightly Wolf & Jones' printed DRO rows pin the mass ratio
# ===============================================================================================================


@dataclass(frozen=True)
class MuStepAnswer:
    """Closures of the printed periodic DRO rows at :math:`\\mu \\pm` step, predicted from the reference step and
    measured.

    All closures are the largest :math:`\\|x(T) - x_0\\|` over the six rows periodic as printed (non-dimensional,
    rotating frame; :func:`~cislunar.papers.wolf_jones.reference_tables.mu_closure_study`).

    Attributes
    ----------
    steps : tuple of float
        The trial values of ``MU_STEP`` (dimensionless), increasing.
    reference_step : float
        The step whose closures the reader has already seen printed (the notebook's default, 1e-9).
    floor : float
        Closure at the adopted :math:`\\mu` (the nine-printed-digit floor).
    slope_bounds : (float, float)
        Bounds on :math:`s = \\max_r \\|\\partial x_r(T)/\\partial\\mu\\|` read from the reference step's closures
        (LU per unit of :math:`\\mu`).
    predicted : dict of float -> (float, float)
        Step -> interval the closure at :math:`\\mu \\pm` step must lie in, to first order in the step.
    measured : dict of float -> (float, float)
        Step -> closures at :math:`\\mu +` step and :math:`\\mu -` step.
    predicted_pass : dict of float -> bool or None
        Step -> ``True`` if the whole predicted interval is below ``tolerance``, ``False`` if it is at or above it,
        ``None`` if the prediction cannot tell.
    measured_pass : dict of float -> bool
        Step -> both closures below ``tolerance`` (what the notebook prints as "closes").
    tolerance : float
        ``CLOSURE_TOL``.
    """

    steps: tuple
    reference_step: float
    floor: float
    slope_bounds: tuple
    predicted: dict
    measured: dict
    predicted_pass: dict
    measured_pass: dict
    tolerance: float
    answer: str


def exercise_01_mu_step(steps=(1e-10, 1e-8), reference_step: float = 1e-9, system=EARTH_MOON) -> MuStepAnswer:
    """Notebook 01, exercise 3: set ``MU_STEP`` to each of ``steps`` and predict the closures printed for
    :math:`\\mu \\pm` ``MU_STEP`` from those of ``reference_step``, and whether they pass ``CLOSURE_TOL``.

    The prediction is first order in the step.  Row *r*'s miss after one period is
    :math:`e_r + J_r\\,\\delta\\mu` with :math:`\\|e_r\\| \\le f` (the floor, the closure at the adopted value) and
    :math:`J_r = \\partial x_r(T)/\\partial\\mu`, so by the triangle inequality the largest closure obeys
    :math:`|c(\\delta\\mu) - s\\,|\\delta\\mu|| \\le f` with :math:`s = \\max_r\\|J_r\\|`.  The reference step's two
    closures bound :math:`s`; the same inequality then gives an interval for every other step.

    Parameters
    ----------
    steps : sequence of float
        Trial values of ``MU_STEP`` (dimensionless, 0 < step < mu), in any order.
    reference_step : float
        Step whose closures fix the slope (dimensionless, 0 < step < mu; the notebook's default 1e-9).
    system : CR3BP
        The adopted system (Earth-Moon by default).

    Raises
    ------
    ValueError
        A step (or ``reference_step``) that is not in ``(0, mu)``: the study tries :math:`\\mu -` step, which
        must stay a valid mass ratio; or ``steps`` containing ``reference_step``.
    """
    check_system(system)
    mu = system.mu
    trial_steps = tuple(sorted({validation.in_range(v, "steps", 0.0, mu, closed=False) for v in
                                validation.as_array(steps, "steps", ndim=(1,), min_size=1).tolist()}))
    ref = validation.in_range(reference_step, "reference_step", 0.0, mu, closed=False)
    if ref in trial_steps:
        raise ValueError(f"steps must not contain reference_step {ref!r}; got {steps!r}")
    every = (ref, *trial_steps)
    study = wjt.mu_closure_study(system, [mu] + [mu + sign * d for d in every for sign in (1, -1)])
    floor = study.adopted_closure
    measured = {d: (study.closure[mu + d], study.closure[mu - d]) for d in every}
    # s is within f of each reference closure divided by the reference step
    s_lo = max(0.0, *((c - floor) / ref for c in measured[ref]))
    s_hi = min((c + floor) / ref for c in measured[ref])
    tol = study.tolerance
    predicted, predicted_pass, measured_pass = {}, {}, {}
    for d in trial_steps:
        lo, hi = max(0.0, s_lo * d - floor), s_hi * d + floor
        predicted[d] = (lo, hi)
        predicted_pass[d] = True if hi < tol else (False if lo >= tol else None)
        measured_pass[d] = bool(max(measured[d]) < tol)
    resolution = (tol - floor) / (0.5 * (s_lo + s_hi))
    lines = []
    for d in trial_steps:
        (lo, hi), (cp, cm) = predicted[d], measured[d]
        verdict = {True: "closes", False: "fails", None: "cannot tell"}[predicted_pass[d]]
        lines.append(f"MU_STEP = {d:.0e}: predicted {lo:.1e} to {hi:.1e} ({verdict}), printed {cp:.1e} and {cm:.1e} "
                     f"({'closes' if measured_pass[d] else 'fails'})")
    answer = (f"At the adopted mu the rows close to {floor:.1e} (the floor of nine printed digits); at mu +- "
              f"{ref:.0e} they miss by {measured[ref][0]:.1e} and {measured[ref][1]:.1e}. The miss of each row is the "
              "floor plus the period map's sensitivity to mu times the step, so away from the floor the closure grows "
              f"linearly with the step, with a slope between {s_lo:.0f} and {s_hi:.0f} LU per unit of mu, and never "
              f"strays from slope x step by more than the floor. Hence: " + "; ".join(lines) + f". The closure reaches CLOSURE_TOL = {tol:.0e} at a step of about (CLOSURE_TOL - floor) / slope = "
              f"{resolution:.0e}: a smaller step stays within the floor's reach and the rows still close (the tables do not resolve "
              "it), a larger one fails. The printed rows therefore pin mu to within a few times 1e-10, which is why the "
              f"chapter's mu row asks every trial at least {wjt.MU_PIN_OFFSET:.1e} away to fail.")
    return MuStepAnswer(trial_steps, ref, floor, (s_lo, s_hi), predicted, measured, predicted_pass, measured_pass,
                        tol, answer)


# End of notebook 01
# ===============================================================================================================


# ===============================================================================================================
# Notebooks 02-04: mutual information, SCvx, Sundman nodes
# ===============================================================================================================

# ---------------------------------------------------------------------------------------------------------------
# 02 · Mutual information
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class MonteCarloSamplesAnswer:
    """Standard error of the joint Monte Carlo estimate of the scalar example's MI at ``n`` and ``factor * n`` samples.

    ``ratio`` is the measured standard-error ratio (small over large sample), ``predicted_ratio`` is
    ``sqrt(factor)``; ``misses`` are ``|estimate - closed form|`` in standard errors, for both runs.
    """

    n_samples: int
    factor: int
    closed: float
    estimates: tuple
    standard_errors: tuple
    ratio: float
    predicted_ratio: float
    misses: tuple
    answer: str


def exercise_02_monte_carlo_samples(n_samples: int = 4000, factor: int = 4, seed: int = 0) -> MonteCarloSamplesAnswer:
    """Notebook 02, exercise 1: multiply ``MC_SAMPLES`` by ``factor``; the standard error falls by ``sqrt(factor)``.

    Runs :func:`~cislunar.papers.wolf_jones.mutual_information_study.scalar_worked_example` (p = 4, h = r = 1) with
    ``n_samples`` and ``factor * n_samples`` samples, each from a generator seeded ``seed``.
    """
    n = validation.integer(n_samples, "n_samples", minimum=100)
    f = validation.integer(factor, "factor", minimum=2)
    seed = validation.integer(seed, "seed", minimum=0)
    runs = [mi_study.scalar_worked_example(m, np.random.default_rng(seed)) for m in (n, f * n)]
    se = tuple(r.monte_carlo_se for r in runs)
    ratio = se[0] / se[1]
    misses = tuple(abs(r.monte_carlo - r.closed) / r.monte_carlo_se for r in runs)
    answer = (f"The Monte Carlo mean of ln p(y|x) - ln p(y) is an average of independent samples, so its standard "
              f"error falls as 1/sqrt(n): {f}x the samples should shrink it {np.sqrt(f):.2f}x. Measured: "
              f"{se[0]:.4f} nats at n = {n}, {se[1]:.4f} nats at n = {f * n}, a ratio of {ratio:.2f}. Both "
              f"estimates stay within a few standard errors of the closed form {runs[0].closed:.4f} nats "
              f"({misses[0]:.1f} and {misses[1]:.1f} standard errors), so the row's tolerance (3 standard errors) "
              f"tightens with the samples while the verdict stays the same.")
    return MonteCarloSamplesAnswer(n, f, runs[0].closed, tuple(r.monte_carlo for r in runs), se, float(ratio),
                                   float(np.sqrt(f)), misses, answer)


@dataclass(frozen=True)
class RangeNoiseAnswer:
    """MI of test case 2's window at Table 5's range noise and at ``factor`` times it (nats).

    ``bound`` is ``n_range ln(1 / factor)``: the largest possible gain when each of the ``n_range`` range
    measurements has its noise standard deviation multiplied by ``factor < 1``.  ``daily_gain`` is the increase of
    each day's chain-rule term (Eq. 18 measurement by measurement) in units of the per-day bound ``3 ln(1/factor)``
    (three range measurements a day): 1 means every range measurement of that day gained the most it could.
    """

    factor: float
    n_days: int
    n_range: int
    mi_table5: float
    mi_scaled: float
    gain: float
    bound: float
    daily_gain: np.ndarray
    answer: str


def exercise_02_range_noise(factor: float = 0.5, n_days: int | None = None) -> RangeNoiseAnswer:
    """Notebook 02, exercise 2: scale the range noise (``RANGE_SIGMA_KM``) by ``factor`` < 1 and predict the MI.

    With whitened measurements, Eq. 18 is ``0.5 ln|I + W|``; scaling the range rows of the noise by ``factor`` turns
    ``W`` into ``D W D`` with ``D = 1/factor`` on those rows, and ``|I + D W D| = |D|^2 |D^-2 + W| <= |D|^2 |I + W|``:
    the MI rises (less noise, more information) but by at most ``ln(1/factor)`` nats per range measurement, a bound
    reached by a measurement far more precise than what is known before it (high signal-to-noise ratio).  Runs on
    the first ``n_days`` daily measurement times of the window (3 targets each; ``None``: the whole window).
    """
    factor = validation.in_range(factor, "factor", 0.0, 1.0, closed=False)
    em = EARTH_MOON
    t = None
    if n_days is not None:
        n_days = validation.integer(n_days, "n_days", minimum=1)
        p_ref = mi_study.reference_period(em)
        t = p_ref + np.arange(n_days) * float(em.days_to_tu(1.0))
    values, terms = [], []
    for sigma in (meas.WOLF_JONES_RANGE_SIGMA_KM, factor * meas.WOLF_JONES_RANGE_SIGMA_KM):
        total, per_time = info.mutual_information(*mi_study.case_2_window(em, t, range_sigma_km=sigma).lin.arrays,
                                                  return_terms=True)
        values.append(float(total))
        terms.append(np.asarray(per_time))
    n_times = terms[0].size
    n_range = 3 * n_times
    gain, bound = values[1] - values[0], n_range * np.log(1 / factor)
    daily = (terms[1] - terms[0]) / (3 * np.log(1 / factor))
    full = int(np.argmax(daily < 0.99)) if np.any(daily < 0.99) else n_times
    answer = (f"Multiplying the range noise by {factor:g} multiplies each range measurement's signal-to-noise ratio "
              f"by {1 / factor**2:g}; a measurement far more precise than what is already known gains "
              f"0.5 ln({1 / factor**2:g}) = {np.log(1 / factor):.3f} nats, and no measurement gains more. Over "
              f"{n_times} daily measurement times ({n_range} range measurements) the bound is {bound:.2f} nats; the "
              f"MI rises from {values[0]:.2f} to {values[1]:.2f} nats, a gain of {gain:.2f} nats = {gain / bound:.0%} "
              "of the bound. Measurement by measurement (chain rule): ")
    if full < n_times:
        answer += (f"the first {full} day(s) gain the full bound (100 m against a 100 km prior), the later days "
                   f"{daily[full:].mean():.0%} of it on average ({daily[full:].min():.0%}-{daily[full:].max():.0%}): "
                   "once the filter has pinned down what a range measurement sees, the next one is no longer far "
                   "more precise than what is known along its direction, and halving its noise buys less.")
    else:
        answer += "every day gains the full bound: 100 m against a 100 km prior."
    return RangeNoiseAnswer(float(factor), n_times, n_range, values[0], values[1], float(gain), float(bound), daily,
                            answer)


# ---------------------------------------------------------------------------------------------------------------
# 03 · SCvx
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class NodeCountAnswer:
    """Converged minimum impulse (m/s) and iterations of notebook 03's transfer for each node count."""

    n_nodes: tuple
    impulses_mps: tuple
    iterations: tuple
    max_defects: tuple
    answer: str


def exercise_03_node_count(n_nodes=(12, 24), sigma: float = 1.0) -> NodeCountAnswer:
    """Notebook 03, exercise 1: halve ``N_NODES`` and predict the converged minimum impulse.

    Solves the transfer on each node count of ``n_nodes`` (ascending) from the ballistic guess.
    """
    counts = tuple(sorted(_checks.integers(n_nodes, "n_nodes", minimum=6)))
    if len(counts) < 2:
        raise ValueError("n_nodes needs at least two node counts")
    sigma = validation.positive(sigma, "sigma", allow_zero=True)
    runs = [scvx_study.solve(scvx_study.transfer_problem(n, sigma)) for n in counts]
    mps = EARTH_MOON.velocity_unit_km_s * 1e3
    imp = tuple(float(r.impulse * mps) for r in runs)
    answer = ("The node controls are the only freedom: with first-order hold the thrust is piecewise linear "
              "between nodes, so fewer nodes give a coarser thrust profile that must start and stop on a coarser "
              "grid, and the same boundary conditions cost more. Measured: "
              + ", ".join(f"{imp[k]:.4f} m/s on {n} nodes" for k, n in enumerate(counts))
              + f"; the impulse falls as nodes are added ({imp[0] / imp[-1]:.2f}x from {counts[0]} to {counts[-1]}), "
              "with diminishing returns, and every run closes its defects. The grids are not nested (Sundman "
              "nodes with the window ends moved onto nodes), so this is an observation, not a theorem.")
    return NodeCountAnswer(counts, imp, tuple(len(r.history) for r in runs),
                           tuple(float(r.max_defect) for r in runs), answer)


@dataclass(frozen=True)
class ThrustBoundAnswer:
    """Minimum impulse (m/s) with Table 3's bound and with ``scale`` times it; the largest converged thrust over the
    bound (``thrust_fraction``, at Table 3's bound)."""

    n_nodes: int
    scale: float
    impulse_table3_mps: float
    impulse_scaled_mps: float
    thrust_fraction: float
    relative_difference: float
    answer: str


def exercise_03_thrust_bound(scale: float = 0.01, n_nodes: int = 12) -> ThrustBoundAnswer:
    """Notebook 03, exercise 2: multiply the thrust bound (``A_MAX_KM_S2``) by ``scale`` and predict the impulse.

    A bound that the optimum does not touch does not change it: if the largest converged thrust is below ``scale``
    times the bound, the impulse stays the same.
    """
    scale = validation.in_range(scale, "scale", 0.0, 1.0, closed=False)
    n = validation.integer(n_nodes, "n_nodes", minimum=6)
    a_max = scenarios.A_MAX_CASE1_KM_S2
    problems = [scvx_study.transfer_problem(n), scvx_study.transfer_problem(n, a_max_km_s2=scale * a_max)]
    runs = [scvx_study.solve(p, scvx.SCvxSettings()) for p in problems]
    mps = EARTH_MOON.velocity_unit_km_s * 1e3
    fraction = float(np.max(np.linalg.norm(runs[0].u, axis=1)) / problems[0].scenario.a_max)
    imp = [float(r.impulse * mps) for r in runs]
    rel = abs(imp[1] - imp[0]) / imp[0]
    answer = (f"The converged thrust never comes near the bound: its largest value is {fraction:.2%} of Table 3's "
              f"a_max (the figure of section 3 shows a_max off the scale). A constraint that is not active at the "
              f"optimum can be tightened down to that level without moving the optimum, so the bound x{scale:g} "
              f"leaves the impulse at {imp[1]:.4f} m/s against {imp[0]:.4f} m/s (relative difference {rel:.1e}, "
              f"on {n} nodes). Only below about {fraction:.1e} x a_max would the bound bite and the impulse rise.")
    return ThrustBoundAnswer(n, float(scale), imp[0], imp[1], fraction, float(rel), answer)


# ---------------------------------------------------------------------------------------------------------------
# 04 · Sundman nodes
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ControlSizeAnswer:
    """Linearisation error (km) of the affine model on the DRO with uniform nodes, for controls of size ``a`` and
    ``a / factor``; the model is exact to first order, so the ratio should be ``factor**2``."""

    n_nodes: int
    factor: float
    error_km: float
    error_reduced_km: float
    ratio: float
    answer: str


def exercise_04_control_size(factor: float = 2.0, n_nodes: int = 24, draws: int = 4,
                             seed: int = 0) -> ControlSizeAnswer:
    """Notebook 04, exercise 1: divide the control size (``CONTROL_SIZE_KM_S2``) by ``factor``; the error falls
    by ``factor**2`` (the affine model is the first-order expansion, so what it misses is second order)."""
    f = validation.positive(factor, "factor")
    if f <= 1:
        raise ValueError(f"factor must be above 1; got {factor!r}")
    n_nodes = validation.integer(n_nodes, "n_nodes", minimum=3)
    draws = validation.integer(draws, "draws", minimum=1)
    seed = validation.integer(seed, "seed", minimum=0)
    em = EARTH_MOON
    arcs = nodes_study.reference_arcs(em)
    dro = {nodes_study.DRO_ARC: arcs[nodes_study.DRO_ARC]}
    t = nodes_study.node_sweep(em, dro, [0.0], n_nodes).nodes[nodes_study.DRO_ARC, 0.0]
    a = nodes_study.A_MAX_KM_S2 / em.acceleration_unit_km_s2
    x0 = dro[nodes_study.DRO_ARC][0]
    e = [nodes_study.linearisation_error(em, x0, t, draws, np.random.default_rng(seed), a / d) for d in (1.0, f)]
    ratio = e[0] / e[1]
    answer = (f"The affine model of Eq. 28 is the first-order expansion of the flow in the controls, so the error "
              f"it leaves is second order: dividing the control size by {f:g} should divide the error by "
              f"{f**2:g}. Measured on the DRO with {n_nodes} uniform nodes (the same {draws} random profiles): "
              f"{e[0]:.3e} km at a_max, {e[1]:.3e} km at a_max / {f:g}, a ratio of {ratio:.2f}. This is why SCvx "
              "can trust the model inside a trust region, and why a trust region must shrink when the ratio test "
              "fails.")
    return ControlSizeAnswer(int(n_nodes), float(f), float(e[0]), float(e[1]), float(ratio), answer)


@dataclass(frozen=True)
class NodeSpacingAnswer:
    """Linearisation error (km) on the DRO with uniform nodes for ``n_nodes`` and ``2 * n_nodes`` nodes, and the
    order ``p`` of the measured decay (error proportional to ``h**p`` for interval length ``h``)."""

    n_nodes: int
    error_km: float
    error_doubled_km: float
    ratio: float
    order: float
    answer: str


def exercise_04_node_count(n_nodes: int = 24, draws: int = 4, seed: int = 0) -> NodeSpacingAnswer:
    """Notebook 04, exercise 2: double ``N_NODES`` and predict the linearisation error.

    Over an interval of length ``h`` a control of size ``a`` displaces the state by about ``a h^2``; the affine model
    misses the second-order term, quadratic in that displacement (``a^2 h^4``) and accumulated over the interval as
    velocity (``h``) and then position (``h``): about ``a^2 h^6``.  Halving every interval should divide the error by
    about ``2^6 = 64``.
    """
    n = validation.integer(n_nodes, "n_nodes", minimum=6)
    draws = validation.integer(draws, "draws", minimum=1)
    seed = validation.integer(seed, "seed", minimum=0)
    em = EARTH_MOON
    arcs = nodes_study.reference_arcs(em)
    dro = {nodes_study.DRO_ARC: arcs[nodes_study.DRO_ARC]}
    x0 = dro[nodes_study.DRO_ARC][0]
    a = nodes_study.A_MAX_KM_S2 / em.acceleration_unit_km_s2
    e = []
    for m in (n, 2 * n - 1):  # 2n - 1 nodes: every interval of the n-node grid halved
        t = nodes_study.node_sweep(em, dro, [0.0], m).nodes[nodes_study.DRO_ARC, 0.0]
        e.append(nodes_study.linearisation_error(em, x0, t, draws, np.random.default_rng(seed), a))
    ratio = e[0] / e[1]
    order = float(np.log2(ratio))
    answer = (f"Halving every interval (from {n} to {2 * n - 1} uniform nodes on the DRO) divides the largest "
              f"one-interval error from {e[0]:.3e} km to {e[1]:.3e} km, a factor of {ratio:.0f}: the error decays as "
              f"h^{order:.1f}, close to the h^6 of the estimate (a displacement a h^2 per interval, squared, and "
              "integrated twice over the interval). Node count is therefore a far stronger lever on the accuracy "
              "of the convex model than the Sundman exponent, which only moves a fixed number of nodes around; "
              "the cost is a larger subproblem at every SCvx iteration.")
    return NodeSpacingAnswer(n, float(e[0]), float(e[1]), float(ratio), order, answer)


# ===============================================================================================================
# End of notebooks 02-04
# ===============================================================================================================


# ===============================================================================================================
# Notebooks 05-06: Wolf & Jones test cases 1 and 2
# ===============================================================================================================

__all__ += [
    "ClosePassAnswer",
    "FreeRunIterationsAnswer",
    "MinimumImpulseNodesAnswer",
    "PenaltyIterationsAnswer",
    "exercise_05_node_count",
    "exercise_05_penalty_iterations",
    "exercise_06_close_pass_scan",
    "exercise_06_free_run_iterations",
]

# ---------------------------------------------------------------------------------------------------------------
# 05 · Test case 1
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class MinimumImpulseNodesAnswer:
    """The minimum-impulse plan (alpha_h = 0) of test case 1 on Sundman grids of ``n_nodes`` nodes.

    ``impulse_mps`` is the total impulse (m/s) and ``rms_km`` the observer's terminal position RMS of the CRLB (km)
    per grid, in the order of ``n_nodes``.
    """

    n_nodes: tuple
    impulse_mps: tuple
    rms_km: tuple
    answer: str


def exercise_05_node_count(n_nodes=(10, 14, 18), sigma: float = 1.0) -> MinimumImpulseNodesAnswer:
    """Notebook 05, exercise 1: change ``N_NODES`` and predict the impulse of the minimum-impulse plan.

    The controls are node accelerations with a first-order hold between nodes; a grid with fewer nodes offers a
    coarser family of thrust profiles, so the smallest impulse that reaches x_S(t_f) with the window coasted can
    only be found at a higher value (the Sundman grids are not nested, so this is a tendency, not a theorem).
    Solves alpha_h = 0 with the chapter's modified SCvx from the ballistic DRO on each grid of ``n_nodes``
    (increasing) nodes.
    """
    counts = _checks.integers(n_nodes, "n_nodes", minimum=6)
    if len(counts) < 2 or any(b <= a for a, b in zip(counts, counts[1:])):
        raise ValueError(f"n_nodes must hold at least two increasing node counts; got {n_nodes!r}")
    sigma = validation.real(sigma, "sigma")
    sc = scenarios.test_case_1()
    mps = sc.system.velocity_unit_km_s * 1e3
    info_model = sc.information_model()
    info_model.hessian_scheme = "forward"
    impulse, rms = [], []
    for n in counts:
        t, k_ws, _ = sc.node_times(n, sigma)
        solver = scenarios.ScenarioSolver(sc, t, k_ws, information=info_model, settings=scvx.SCvxSettings())
        res = solver(0.0, *sc.ballistic_guess(t))
        impulse.append(float(res.impulse * mps))
        rms.append(float(scenarios.evaluate_crlb(sc, res.x[k_ws]).terminal_rms_km[0]))
    answer = ("Fewer nodes, more impulse: the minimum-impulse plan spends "
              + ", ".join(f"{v:.3f} m/s on {n} nodes" for n, v in zip(counts, impulse))
              + ". A coarser grid gives the first-order-hold control fewer places to thrust, so the cheapest transfer "
              "it can represent costs more; the gain from each added node shrinks as the grid approaches the "
              "continuous optimum (the plans are nearly impulsive, a few single-node spikes). The terminal RMS of "
              "these plans (" + ", ".join(f"{v:.0f} km" for v in rms) + f") moves much less (a spread of "
              f"{100 * (max(rms) / min(rms) - 1):.0f} % against {100 * (max(impulse) / min(impulse) - 1):.0f} % for "
              "the impulse): at alpha_h = 0 the observer stays close to its DRO and what it learns is set by that "
              "orbit more than by the grid. Halving N_NODES in the notebook therefore moves the left end of the "
              "Pareto front of Fig. 5 to the right (more impulse) and little up or down.")
    return MinimumImpulseNodesAnswer(counts, tuple(impulse), tuple(rms), answer)


@dataclass(frozen=True)
class PenaltyIterationsAnswer:
    """The paper's exact-penalty SCvx (L1 penalty ``gamma``, linear MI model of Eq. 44) at two iteration limits.

    Per limit in ``max_iter``: ``converged``, the last largest defect (LU), the last trust-region radius ``eta``
    and the best accepted cost.
    """

    n_nodes: int
    alpha: float
    gamma: float
    max_iter: tuple
    converged: tuple
    last_defect: tuple
    last_eta: tuple
    best_cost: tuple
    answer: str


def _prefix_runs(converged: bool, history: list, limits) -> list:
    """``(converged, history)`` of SCvx runs with each iteration limit of ``limits``, read off one run at the largest.

    SCvx is deterministic and its iteration limit only ends the loop, so a run limited to ``m`` iterations repeats
    the first ``m`` iterations of the longer run (one history record per iteration): if the long run stopped
    (converged, or raised) within ``m`` iterations the short one stops the same way with the same history;
    otherwise it ends unconverged after the first ``m`` records.  Bit-identical to separate runs
    (tests/papers/wolf_jones/test_exercises_wolf_jones.py).
    """
    return [(converged, history) if len(history) <= m else (False, history[:m]) for m in limits]


def exercise_05_penalty_iterations(max_iter=(10, 30), *, n_nodes: int = 10, alpha: float = 5e-3,
                                   gamma: float = 1e3) -> PenaltyIterationsAnswer:
    """Notebook 05, exercise 2: raise ``PENALTY_ITER_LONG`` and predict whether the printed method converges.

    Runs the printed method (``method="penalty"``, ``information_model="linear"``) from the ballistic DRO of test
    case 1 on ``n_nodes`` Sundman nodes at each iteration limit of ``max_iter`` (increasing).
    """
    limits = _checks.integers(max_iter, "max_iter", minimum=1)
    if len(limits) != 2 or limits[1] <= limits[0]:
        raise ValueError(f"max_iter must be two increasing iteration limits; got {max_iter!r}")
    n = validation.integer(n_nodes, "n_nodes", minimum=6)
    alpha = validation.in_range(alpha, "alpha", 0.0, 1.0)
    gamma = validation.positive(gamma, "gamma")
    sc = scenarios.test_case_1()
    t, k_ws, _ = sc.node_times(n, 1.0)
    x_ball, u_ball = sc.ballistic_guess(t)
    info_model = sc.information_model()
    u_max = sc.control_bounds(t)
    st = scvx.SCvxSettings(method="penalty", information_model="linear", defect_weight=float(gamma),
                           max_iter=limits[-1])
    try:  # one run at the larger limit: the shorter run is its prefix (_prefix_runs)
        r = scvx.solve_scvx(sc.system, t, x_ball, u_ball, u_max, x_final=sc.observer_xf, info=info_model,
                            info_node=k_ws, alpha=float(alpha), settings=st)
        long_hist, long_ok = r.history, True
    except scvx.SCvxError as exc:
        long_hist, long_ok = exc.history, False
    conv, defect, eta, best = [], [], [], []
    for ok, hist in _prefix_runs(long_ok, long_hist, limits):
        conv.append(ok)
        defect.append(float(hist[-1]["max_defect"]))
        eta.append(float(hist[-1]["eta"]))
        accepted = [h["new_cost"] for h in hist if h["accepted"]]
        best.append(float(min(accepted)) if accepted else float("nan"))  # NaN: no step accepted within the limit
    answer = (f"More iterations do not make the printed method converge: with {limits[0]} and {limits[1]} "
              f"iterations (gamma = {gamma:g}, alpha_h = {alpha:g}, {n} nodes) it converges "
              f"{'in neither run' if not any(conv) else 'in ' + str(sum(conv)) + ' run(s)'}. What the extra "
              f"iterations buy is slow creep: the largest defect falls from {defect[0]:.1e} to {defect[1]:.1e}, the "
              f"best accepted cost from {best[0]:.5f} to {best[1]:.5f}, while the trust region keeps shrinking "
              f"(eta {eta[0]:.1e} -> {eta[1]:.1e}). The ratio test keeps cutting the radius because the convex "
              "model (linear MI of Eq. 44, L1 penalty on the defects) mispredicts the true change of the cost, and "
              "the defects can then close only as fast as the shrinking steps allow. The notebook's long run (300 "
              "iterations in full mode) shows the same picture.")
    return PenaltyIterationsAnswer(n, float(alpha), float(gamma), limits, tuple(conv), tuple(defect), tuple(eta),
                                   tuple(best), answer)


# ---------------------------------------------------------------------------------------------------------------
# 06 · Test case 2
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ClosePassAnswer:
    """MI gain (nats) of test case 2's window when the observer passes target 1 at ``d_km`` at the middle
    measurement; ``slope`` is the fitted gain per e-fold of closer distance (nats), ``per_decade`` per factor 10."""

    d_km: np.ndarray
    gain: np.ndarray
    slope: float
    per_decade: float
    answer: str


def exercise_06_close_pass_scan(d_range_km=(1e-6, 1e-2), n_points: int = 7) -> ClosePassAnswer:
    """Notebook 06, exercise 1: set ``SCAN_RANGE_KM`` to close passes only and predict the MI gain per decade.

    Near a target the range-rate Jacobian grows like 1/rho, so one range-rate measurement's Fisher information grows
    like 1/rho^2 and its MI term ``0.5 ln(1 + c/rho^2)`` like ``ln(1/rho)``: one nat per e-fold closer, ``ln 10 =
    2.30`` nats per decade, without bound.  Runs the chapter's scan (:func:`test_case_studies.keep_out_scan`) from
    the ballistic window-start state.
    """
    lo, hi = (float(v) for v in validation.as_array(d_range_km, "d_range_km", shape=(2,)))
    if not 0 < lo < hi:
        raise ValueError(f"d_range_km must be (closest, farthest) with 0 < closest < farthest; got {d_range_km!r}")
    n = validation.integer(n_points, "n_points", minimum=3)
    sc = scenarios.test_case_2()
    info_model = sc.information_model()
    t, k_ws, _ = sc.node_times(12, 1.0)
    x_ws = sc.ballistic_guess(t)[0][k_ws]
    scan = tc_studies.keep_out_scan(sc, info_model, x_ws, n, d_range_km=(lo, hi))
    slope = float(-np.polyfit(np.log(scan.d_km), scan.gain, 1)[0])
    answer = (f"Each factor of 10 closer adds {slope * np.log(10):.2f} nats (fitted over {lo:g}-{hi:g} km: "
              f"{slope:.3f} nats per e-fold), the ln 10 = 2.30 of the prediction: the MI of a range-rate "
              "measurement grows like ln(1/rho) as the range rho shrinks, because its Jacobian with respect to the "
              "relative position grows like 1/rho. The reward is unbounded: a maximiser that finds this region would "
              "fly through the target, which is why the chapter needs a keep-out, and why its size (not this "
              "singularity) decides where the optima lie.")
    return ClosePassAnswer(scan.d_km, scan.gain, slope, float(slope * np.log(10)), answer)


@dataclass(frozen=True)
class FreeRunIterationsAnswer:
    """SCvx without a keep-out at ``alpha`` on ``n_nodes`` nodes, at two iteration limits: converged, last largest
    defect (LU), best accepted cost and the closest approach (km) of the last reference to a target."""

    n_nodes: int
    alpha: float
    max_iter: tuple
    converged: tuple
    last_defect: tuple
    best_cost: tuple
    last_range_km: tuple
    answer: str


def exercise_06_free_run_iterations(max_iter=(10, 30), *, n_nodes: int = 12,
                                    alpha: float = 1e-2) -> FreeRunIterationsAnswer:
    """Notebook 06, exercise 2: raise ``FREE_ITER`` and predict whether the run without keep-out converges.

    Runs :func:`test_case_studies.free_run` from the ballistic guess at each iteration limit of ``max_iter``.
    """
    limits = _checks.integers(max_iter, "max_iter", minimum=1)
    if len(limits) != 2 or limits[1] <= limits[0]:
        raise ValueError(f"max_iter must be two increasing iteration limits; got {max_iter!r}")
    n = validation.integer(n_nodes, "n_nodes", minimum=6)
    alpha = validation.in_range(alpha, "alpha", 0.0, 1.0)
    sc = scenarios.test_case_2()
    info_model = sc.information_model()
    t, k_ws, _ = sc.node_times(n, 1.0)
    x_ball, u_ball = sc.ballistic_guess(t)
    # one run at the larger limit: the shorter run is its prefix (_prefix_runs)
    run = tc_studies.free_run(sc, t, k_ws, info_model, float(alpha), x_ball, u_ball, limits[-1])
    conv, defect, best, last = [], [], [], []
    for ok, hist in _prefix_runs(not run.failed, run.outcome.history, limits):
        conv.append(ok)
        defect.append(float(run.outcome.max_defect) if ok else float(hist[-1]["max_defect"]))
        acc = [h["new_cost"] for h in hist if h.get("accepted")]
        best.append(float(run.outcome.cost) if ok else float(min(acc)) if acc else float("nan"))
        # the references are the starting guess and the state after each accepted step that did not end the run:
        # a prefix cut before the end holds 1 + (its accepted steps) of them, the whole run all of them
        n_refs = run.ref_range_km.size if hist is run.outcome.history else 1 + sum(bool(h["accepted"]) for h in hist)
        last.append(float(run.ref_range_km[n_refs - 1]))
    conv, defect, best, last = tuple(conv), tuple(defect), tuple(best), tuple(last)
    answer = (f"Without a keep-out, more iterations do not bring convergence: after {limits[0]} and {limits[1]} "
              f"iterations (alpha_h = {alpha:g}, {n} nodes) the run "
              f"{'has not converged in either' if not any(conv) else 'converged in ' + str(sum(conv))}. The best "
              f"accepted cost {'sinks further' if best[1] < best[0] else 'stops improving'} ({best[0]:.5f} -> "
              f"{best[1]:.5f}; it cannot rise, the longer run repeats the shorter one first) while the defects stay "
              f"open ({defect[0]:.1e} -> {defect[1]:.1e}): the steps buy information rather than close the "
              "dynamics, because the MI "
              "rewards flying ever closer to a target (exercise 1: one nat per e-fold, without bound). The closest "
              f"approach of the last reference to a target moves from {last[0]:.0f} km to {last[1]:.0f} km. A "
              "keep-out turns the reward bounded and the problem solvable; the notebook's row 'SCvx converges "
              "without a keep-out' differs for this reason, at every iteration limit tried.")
    return FreeRunIterationsAnswer(n, float(alpha), limits, conv, defect, best, last, answer)


# ===============================================================================================================
# End of notebooks 05-06
# ===============================================================================================================

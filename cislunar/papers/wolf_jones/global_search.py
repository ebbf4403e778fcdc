"""Global quality of the Wolf & Jones SCvx solutions (issue 22, item 1): multi-start, lower envelope, mesh study.

The weighted-sum problem :math:`J = (1-\\alpha_h)\\,\\mathrm{impulse} - \\alpha_h\\mathcal I` of test cases 1 and 2
is non-convex, so one SCvx run per weight returns *a* local optimum.  This module

* starts SCvx several times per weight (:func:`multi_start`: the ballistic guess, +z and -z seeds, random control
  perturbations drawn from a generator passed in, the optimum of each neighbouring weight, and any plans already
  known such as the homotopy sweep's), keeps the lowest cost and counts the distinct local optima;
* draws the Pareto front as the lower envelope of every optimum found (:func:`lower_envelope`, monotone by
  construction; :func:`front_points` evaluates the CRLB of each distinct optimum);
* solves the headline weights again on several Sundman grids (:func:`mesh_study`) and moves the finer grids'
  plans back onto the figures' grid as further starts there (:func:`back_to_grid`, :func:`with_starts`,
  :func:`with_moved_back`).

**Same or distinct optimum** (fixed before any run).  Two converged plans at one weight are *the same local optimum*
when their costs agree within ``cost_tol (1 + max |J|)`` (default ``cost_tol`` = 1e-6, a hundred times the solver's
stopping tolerance of 1e-8) **and** their node positions, or those of one and the z-mirror of the other (the
problem is symmetric under :math:`z\\to-z`, so mirror images are one optimum), are never farther apart than
``plan_km`` (default 100 km, the threshold notebook 06 uses for "the same plan").  Otherwise they are *distinct*.

Every solve is deterministic and the random perturbations are drawn in the calling process, in a fixed order, before
anything is queued; results are therefore bit-identical whatever the ``executor`` (None: serial; a
``concurrent.futures`` pool or a Dask client from :func:`cislunar.utils.executors.open_executor`).

Units: impulses in m/s, MI in nats, RMS and distances in km, costs non-dimensional (LU/TU for the impulse part);
states are rotating-frame barycentric CR3BP states in LU and LU/TU, controls in LU/TU^2.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp.propagation import ImpactError
from cislunar.guidance import discretization as D
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import _checks
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.utils import montecarlo, validation

__all__ = ["StartOutcome", "MultiStart", "multi_start", "with_starts", "known_from_sweep", "adopt", "Envelope",
           "lower_envelope", "FrontPoints", "front_points", "MeshRow", "MeshStudy", "mesh_study", "back_to_grid",
           "with_moved_back", "MeshStarts", "mesh_starts"]

_MIRROR = np.diag([1, 1, -1, 1, 1, -1.0])


def _mps(system) -> float:
    return system.velocity_unit_km_s * 1e3


# --------------------------------------------------------------------------------------------------------------
# multi-start
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class StartOutcome:
    """One start of :func:`multi_start` at one weight.

    Attributes
    ----------
    alpha : float
    label : str
        ``"ballistic"``, ``"+z seed"``, ``"-z seed"``, ``"random k"``, ``"neighbour <alpha>"`` or a known plan's label.
    converged : bool
    cost : float
        SCvx cost (NaN if not converged).
    impulse_mps : float
        Total impulse, m/s (NaN if not converged).
    mi : float
        Mutual information of the window, nats (NaN if not converged).
    iterations : int
    error : str
        Why the start failed ("" if converged).
    optimum : int
        Index of its distinct local optimum at this weight, 0 the lowest cost (-1 if not converged).
    result : SCvxResult or None
    """

    alpha: float
    label: str
    converged: bool
    cost: float
    impulse_mps: float
    mi: float
    iterations: int
    error: str
    optimum: int
    result: object


@dataclass(frozen=True)
class MultiStart:
    """Every start of :func:`multi_start`, the best plan per weight and the distinct local optima.

    Attributes
    ----------
    alphas : tuple of float
    outcomes : tuple of StartOutcome
        In the order: per weight the known plans, then the generated starts of the first round, then the
        neighbour starts.
    best : tuple of SCvxResult or None
        Lowest-cost converged plan per weight.
    best_label : tuple of str
        The start that gave it.
    cost_tol, plan_km : float
        The same-optimum tolerances (module docstring).
    seconds : float
        Wall time, s.
    """

    alphas: tuple
    outcomes: tuple
    best: tuple
    best_label: tuple
    cost_tol: float
    plan_km: float
    seconds: float

    def at(self, alpha: float) -> list:
        """The outcomes at one weight."""
        return [o for o in self.outcomes if o.alpha == alpha]

    @property
    def n_distinct(self) -> tuple:
        """Number of distinct local optima per weight."""
        return tuple(max((o.optimum for o in self.at(a)), default=-1) + 1 for a in self.alphas)

    @property
    def cost_range(self) -> tuple:
        """``(lowest, highest)`` converged cost per weight (NaN when none converged)."""
        out = []
        for a in self.alphas:
            c = [o.cost for o in self.at(a) if o.converged]
            out.append((min(c), max(c)) if c else (np.nan, np.nan))
        return tuple(out)

    @property
    def n_converged(self) -> tuple:
        return tuple(sum(o.converged for o in self.at(a)) for a in self.alphas)

    def optima(self, alpha: float) -> list:
        """The representative (lowest-cost) outcome of each distinct optimum at ``alpha``, best first."""
        reps = {}
        for o in self.at(alpha):
            if o.converged and (o.optimum not in reps or o.cost < reps[o.optimum].cost):
                reps[o.optimum] = o
        return [reps[k] for k in sorted(reps)]

    def improvements(self, reference) -> list:
        """``(alpha, reference cost, best cost, label)`` where the multi-start beats ``reference`` (a sequence of
        plans or None, one per weight) by more than ``cost_tol (1 + |J|)``."""
        reference = _checks.sequence(reference, "reference")
        if len(reference) != len(self.alphas):
            raise ValueError(f"reference must hold one plan per weight ({len(self.alphas)}); got {len(reference)}")
        out = []
        for a, r, b, lab in zip(self.alphas, reference, self.best, self.best_label):
            if b is not None and (r is None or b.cost < r.cost - self.cost_tol * (1 + abs(r.cost))):
                out.append((a, np.nan if r is None else float(r.cost), float(b.cost), lab))
        return out

    def summary(self) -> str:
        lines = [f"multi-start: {len(self.outcomes)} starts over {len(self.alphas)} weights in {self.seconds:.0f} s; "
                 f"same optimum: cost within {self.cost_tol:g} (1 + |J|) and plans (or z-mirrors) within "
                 f"{self.plan_km:g} km",
                 f"{'alpha_h':>8} {'starts':>6} {'conv':>5} {'optima':>6} {'best cost':>13} {'worst cost':>13} "
                 f"{'best dV m/s':>11} {'best MI':>8}  best from"]
        for a, n_d, (lo, hi), b, lab in zip(self.alphas, self.n_distinct, self.cost_range, self.best, self.best_label):
            at = self.at(a)
            bo = next((o for o in at if o.result is b), None) if b is not None else None
            lines.append(f"{a:8.4g} {len(at):6d} {sum(o.converged for o in at):5d} {n_d:6d} {lo:13.7f} {hi:13.7f} "
                         f"{(bo.impulse_mps if bo else np.nan):11.3f} {(bo.mi if bo else np.nan):8.3f}  {lab}")
        for a in self.alphas:
            opts = self.optima(a)
            if len(opts) > 1:
                lines.append(f"  alpha_h {a:g}: optima " + "; ".join(
                    f"#{o.optimum} cost {o.cost:.6f} ({o.impulse_mps:.2f} m/s, {o.mi:.2f} nats, from {o.label})"
                    for o in opts))
        return "\n".join(lines)


def known_from_sweep(sweep, alphas=None, *, which: str = "best") -> dict:
    """Plans of a :class:`~cislunar.guidance.scvx.SweepResult` for the ``known`` argument of :func:`multi_start`
    (only the weights in ``alphas`` if given).

    ``which="best"``: ``{alpha: [("sweep (up|down)", plan)]}``, the best plan per weight.  ``which="ballistic"``:
    ``{alpha: [("ballistic", plan)]}`` for the weights whose best plan came from a cold start of a
    :func:`~cislunar.papers.wolf_jones.scenarios.sweep_both_ways` sweep (its ``attempts`` name each run's
    ``start``), i.e. from the sweep's own guess: when that guess is the ballistic one (:meth:`Scenario.ballistic_guess`
    on the solver's grid) these are the multi-start's ballistic starts, already solved; merged into ``known`` after
    the other rows they are not solved again (SCvx is deterministic: the same outcome, bit for bit).
    """
    validation.instance(sweep, "sweep", scvx.SweepResult)
    keep = None if alphas is None else {float(a) for a in _checks.vector(alphas, "alphas")}
    which = validation.choice(which, "which", ("best", "ballistic"))
    out = {}
    for a, b, d in zip(sweep.alphas, sweep.best, sweep.source):
        if b is None or (keep is not None and float(a) not in keep):
            continue
        if which == "best":
            out[float(a)] = [(f"sweep ({d})", b)]
            continue
        run = [r for r in sweep.attempts if r["alpha"] == float(a) and r.get("direction") == d and r["converged"]]
        if len(run) == 1 and run[0].get("start") == "cold":
            out[float(a)] = [("ballistic", b)]
    return out


def adopt(sweep, ms: MultiStart):
    """A :class:`~cislunar.guidance.scvx.SweepResult` holding, per weight of ``sweep``, the lower-cost plan of the
    sweep's best and the multi-start's best (``ms`` may cover a subset of the weights), with the sweep's own
    attempts (what the studies of notebooks 05 and 06 read); ``source`` names the start of a multi-start plan."""
    validation.instance(sweep, "sweep", scvx.SweepResult)
    validation.instance(ms, "ms", MultiStart)
    weights = [float(a) for a in sweep.alphas]
    if not set(ms.alphas) <= set(weights):
        raise ValueError(f"ms must be run over weights of the sweep {tuple(weights)}; got {ms.alphas}")
    best, source = list(sweep.best), list(sweep.source)
    for a, b, lab in zip(ms.alphas, ms.best, ms.best_label):
        i = weights.index(a)
        if b is not None and (best[i] is None or b.cost < best[i].cost):
            best[i], source[i] = b, lab
    return scvx.SweepResult(sweep.alphas, best, source, sweep.attempts)


def _solve_task(solver, task):
    """One start: ``task = (alpha, x_guess, u_guess)``; the plan or the :class:`SCvxError` (an iterate whose
    window arc hits a primary ends the start the same way)."""
    alpha, x, u = task
    try:
        return solver(alpha, x, u)
    except scvx.SCvxError as exc:
        return exc
    except ImpactError as exc:
        return scvx.SCvxError(f"an iterate hit a primary ({exc})")


def _random_guess(sc, t, u_max, rng, scale):
    """A control perturbation: per thrust node a Gaussian direction of RMS size ``scale`` a_max (clipped to the
    bound), flown from x_S(t0)."""
    g = rng.standard_normal((t.size, 3)) / np.sqrt(3.0)
    u = scale * u_max[:, None] * g
    n = np.linalg.norm(u, axis=1)
    over = n > u_max
    u[over] *= (u_max[over] / n[over])[:, None]
    return D.propagate_foh(sc.system, sc.observer_x0, t, u), u


def _same(a, b, cost_tol: float, plan_lu: float) -> bool:
    if abs(a.cost - b.cost) > cost_tol * (1 + max(abs(a.cost), abs(b.cost))):
        return False
    d = min(np.max(np.linalg.norm((a.x - b.x)[:, :3], axis=1)),
            np.max(np.linalg.norm((a.x - b.x @ _MIRROR)[:, :3], axis=1)))
    return bool(d <= plan_lu)


def _cluster(results, cost_tol: float, plan_lu: float) -> list:
    """Index of the distinct optimum of each result (None for failures), 0 for the lowest cost."""
    ok = sorted((i for i, r in enumerate(results) if r is not None), key=lambda i: results[i].cost)
    reps, label = [], [None] * len(results)
    for i in ok:
        k = next((k for k, j in enumerate(reps) if _same(results[i], results[j], cost_tol, plan_lu)), None)
        if k is None:
            reps.append(i)
            k = len(reps) - 1
        label[i] = k
    return label


def multi_start(solver, alphas, *, rng=None, n_random: int = 1, random_scale: float = 0.05, seeds_z: bool = True,
                z_fraction: float = 0.05, ballistic: bool = True, neighbours: bool = True, known=None,
                cost_tol: float = 1e-6, plan_km: float = 100.0, executor=None) -> MultiStart:
    """Solve every weight of ``alphas`` from several starts and keep the lowest cost.

    Parameters
    ----------
    solver : ScenarioSolver
        ``solver(alpha, x_guess, u_guess)`` on one node grid (test case 1 or 2).
    alphas : sequence of float
        Strictly increasing homotopy weights in [0, 1].
    rng : numpy.random.Generator, optional
        Draws the random perturbations (needed when ``n_random`` > 0); drawn here, in order, before any solve.
    n_random : int
        Random control perturbations per weight (:math:`u_k \\sim` ``random_scale`` :math:`a_{max}` per node,
        clipped to the bound, flown from x_S(t0)).
    random_scale : float
        RMS size of a perturbation relative to the node's thrust bound, in (0, 1].
    seeds_z : bool
        Start from the +z and -z seeds (:meth:`Scenario.seeded_guess`, ``z_fraction`` a_max out of plane).
    z_fraction : float
    ballistic : bool
        Start from the ballistic guess.
    neighbours : bool
        A second round: each weight warm-started from the best plan of each neighbouring weight after round one.
    known : dict, optional
        ``{alpha: [(label, plan), ...]}`` of plans already solved on this grid (e.g. :func:`known_from_sweep`),
        counted as outcomes without re-solving; a generated start whose label is already known at that weight is
        skipped.
    cost_tol, plan_km : float
        The same-optimum tolerances (module docstring): relative cost, and node-position distance in km.
    executor : optional
        ``submit``-style executor; every round's solves run through it (results do not depend on it).

    Returns
    -------
    MultiStart
    """
    validation.instance(solver, "solver", wj.ScenarioSolver)
    a = validation.as_array(alphas, "alphas", ndim=(1,), min_size=1)
    if np.any(a < 0) or np.any(a > 1) or np.any(np.diff(a) <= 0):
        raise ValueError(f"alphas must be strictly increasing within [0, 1]; got {a}")
    alphas = tuple(float(v) for v in a)
    n_random = validation.integer(n_random, "n_random", minimum=0)
    random_scale = validation.in_range(random_scale, "random_scale", 0.0, 1.0)
    if random_scale == 0.0:
        raise ValueError("random_scale must be in (0, 1]; got 0")
    if n_random and not isinstance(rng, np.random.Generator):
        raise validation.ArgumentTypeError(f"rng must be a numpy.random.Generator when n_random > 0; got "
                                           f"{type(rng).__name__}")
    if rng is not None and not isinstance(rng, np.random.Generator):
        raise validation.ArgumentTypeError(f"rng must be None or a numpy.random.Generator; got {type(rng).__name__}")
    seeds_z = validation.boolean(seeds_z, "seeds_z")
    z_fraction = validation.in_range(z_fraction, "z_fraction", 0.0, 1.0)
    ballistic = validation.boolean(ballistic, "ballistic")
    neighbours = validation.boolean(neighbours, "neighbours")
    cost_tol = validation.positive(cost_tol, "cost_tol")
    plan_km = validation.positive(plan_km, "plan_km")
    _checks.executor(executor)
    known = {} if known is None else validation.instance(known, "known", dict, "a dict {alpha: [(label, plan)]}")
    sc, t = solver.scenario, solver.t
    known_rows = {}
    for k, rows in known.items():
        kf = validation.real(k, "known key")
        if kf not in alphas:
            raise ValueError(f"known holds a weight {k!r} outside alphas {alphas}")
        rows = _checks.sequence(rows, f"known[{k!r}]", allow_empty=True)
        for i, r in enumerate(rows):
            if not isinstance(r, tuple) or len(r) != 2 or not isinstance(r[0], str):
                raise validation.ArgumentTypeError(f"known[{k!r}][{i}] must be a (label, plan) tuple")
            _checks.plan(r[1], f"known[{k!r}][{i}][1]", n=t.size)
        known_rows[kf] = list(rows)
    t0 = time.perf_counter()
    # round one: every generated start, guesses built (and random numbers drawn) here in a fixed order
    guesses = {}
    if ballistic:
        guesses["ballistic"] = sc.ballistic_guess(t)
    if seeds_z:
        guesses["+z seed"] = sc.seeded_guess(t, +1, z_fraction)
        guesses["-z seed"] = sc.seeded_guess(t, -1, z_fraction)
    entries = {al: [(lab, res, "") for lab, res in known_rows.get(al, [])] for al in alphas}
    tasks, where = [], []
    for al in alphas:
        have = {lab for lab, _, _ in entries[al]}
        starts = [(lab, g) for lab, g in guesses.items() if lab not in have]
        for j in range(n_random):
            try:
                starts.append((f"random {j + 1}", _random_guess(sc, t, solver.u_max, rng, random_scale)))
            except RuntimeError as exc:  # the perturbed guess hits a primary (ImpactError) or fails to integrate
                entries[al].append((f"random {j + 1}", None, f"guess not flown: {exc}"))
        for lab, (x, u) in starts:
            tasks.append((al, x, u))
            where.append((al, lab))
    run = functools.partial(_solve_task, solver)
    for (al, lab), out in zip(where, montecarlo.map_tasks(run, tasks, executor=executor, progress=False)):
        entries[al].append((lab, None, out.reason) if isinstance(out, scvx.SCvxError) else (lab, out, ""))

    def best_of(al):
        ok = [r for _, r, _ in entries[al] if r is not None]
        return min(ok, key=lambda r: r.cost) if ok else None

    if neighbours and len(alphas) > 1:
        bests = {al: best_of(al) for al in alphas}
        tasks, where = [], []
        for i, al in enumerate(alphas):
            for j in (i - 1, i + 1):
                if 0 <= j < len(alphas) and bests[alphas[j]] is not None:
                    tasks.append((al, bests[alphas[j]].x, bests[alphas[j]].u))
                    where.append((al, f"neighbour {alphas[j]:g}"))
        for (al, lab), out in zip(where, montecarlo.map_tasks(run, tasks, executor=executor, progress=False)):
            entries[al].append((lab, None, out.reason) if isinstance(out, scvx.SCvxError) else (lab, out, ""))
    return _assemble(alphas, entries, sc.system, cost_tol, plan_km, time.perf_counter() - t0)


def _assemble(alphas, entries, system, cost_tol, plan_km, seconds) -> MultiStart:
    """The :class:`MultiStart` of ``entries`` (``{alpha: [(label, plan or None, error), ...]}``, in start order):
    distinct optima clustered per weight, the lowest cost kept (ties: the earliest start)."""
    mps, outcomes, best, best_label = _mps(system), [], [], []
    for al in alphas:
        rows = entries[al]
        opt = _cluster([r for _, r, _ in rows], cost_tol, plan_km / system.length_unit_km)
        for (lab, r, err), k in zip(rows, opt):
            outcomes.append(StartOutcome(al, lab, r is not None, np.nan if r is None else float(r.cost),
                                         np.nan if r is None else float(r.impulse * mps),
                                         np.nan if r is None else float(r.information),
                                         0 if r is None else int(r.iterations), err, -1 if k is None else k, r))
        ok = [(r.cost, i) for i, (_, r, _) in enumerate(rows) if r is not None]
        if ok:
            i_best = min(ok)[1]  # lowest cost; ties: the earliest start
            best.append(rows[i_best][1])
            best_label.append(rows[i_best][0])
        else:
            best.append(None)
            best_label.append("")
    return MultiStart(alphas, tuple(outcomes), tuple(best), tuple(best_label), cost_tol, plan_km, seconds)


def with_starts(solver, ms: MultiStart, extra: dict) -> MultiStart:
    """``ms`` with more starts per weight, solved elsewhere on the same grid (e.g. the mesh study's plans moved
    back by :func:`back_to_grid`): their outcomes are appended after ``ms``'s own, the distinct optima clustered
    again with ``ms``'s tolerances and the best plan per weight chosen again (ties: the earlier start, so an extra
    start replaces a plan only with a strictly lower cost).

    Parameters
    ----------
    solver : ScenarioSolver
        The solver ``ms`` was run with (its grid and system).
    ms : MultiStart
    extra : dict
        ``{alpha: [(label, outcome), ...]}`` with ``alpha`` among ``ms.alphas``; ``outcome`` a converged
        :class:`~cislunar.guidance.scvx.SCvxResult` on ``ms``'s grid or the :class:`~cislunar.guidance.scvx.SCvxError`
        of a start that failed.

    Returns
    -------
    MultiStart
        Same weights, tolerances and wall time (``seconds``: the extra starts were timed where they ran).
    """
    validation.instance(solver, "solver", wj.ScenarioSolver)
    validation.instance(ms, "ms", MultiStart)
    extra = validation.instance(extra, "extra", dict, "a dict {alpha: [(label, outcome)]}")
    entries = {al: [(o.label, o.result if o.converged else None, o.error) for o in ms.at(al)] for al in ms.alphas}
    for k, rows in extra.items():
        kf = validation.real(k, "extra key")
        if kf not in ms.alphas:
            raise ValueError(f"extra holds a weight {k!r} outside ms.alphas {ms.alphas}")
        for i, r in enumerate(_checks.sequence(rows, f"extra[{k!r}]", allow_empty=True)):
            if not isinstance(r, tuple) or len(r) != 2 or not isinstance(r[0], str):
                raise validation.ArgumentTypeError(f"extra[{k!r}][{i}] must be a (label, outcome) tuple")
            lab, out = r
            if isinstance(out, scvx.SCvxError):
                entries[kf].append((lab, None, out.reason))
            else:
                entries[kf].append((lab, _checks.plan(out, f"extra[{k!r}][{i}][1]", n=solver.t.size), ""))
    return _assemble(ms.alphas, entries, solver.scenario.system, ms.cost_tol, ms.plan_km, ms.seconds)


# --------------------------------------------------------------------------------------------------------------
# lower envelope (Pareto front over every optimum found)
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Envelope:
    """The non-dominated points of a set: ``x`` (to be minimised, e.g. impulse) strictly increasing and ``y``
    strictly decreasing (``sense="min"``, e.g. RMS) or strictly increasing (``sense="max"``, e.g. MI).

    Attributes
    ----------
    x, y : ndarray
        The envelope's points, by increasing ``x``.
    index : ndarray of int
        Their indices in the input.
    sense : str
    """

    x: np.ndarray
    y: np.ndarray
    index: np.ndarray
    sense: str

    @property
    def monotone(self) -> bool:
        dy = np.diff(self.y) * (1 if self.sense == "max" else -1)
        return bool(np.all(np.diff(self.x) > 0) and np.all(dy > 0))


def lower_envelope(x, y, *, sense: str = "min") -> Envelope:
    """The Pareto front of points ``(x_i, y_i)``: less ``x`` is better, and less ``y`` (``sense="min"``) or more
    ``y`` (``sense="max"``).

    A point is kept when no other point is at least as good on both axes and better on one; of exact duplicates one
    is kept (the first).  By construction the result is monotone (:attr:`Envelope.monotone`).

    Parameters
    ----------
    x, y : array_like (n,)
        Finite coordinates (e.g. impulse m/s and terminal RMS km, or impulse and MI nats).
    sense : {"min", "max"}
    """
    x = validation.as_array(x, "x", ndim=(1,), min_size=1)
    y = validation.as_array(y, "y", shape=x.shape)
    validation.choice(sense, "sense", ("min", "max"))
    ys = y if sense == "min" else -y
    order = np.lexsort((np.arange(x.size), ys, x))  # by x, then the better y, then input order
    keep, best = [], np.inf
    for i in order:
        if ys[i] < best:
            keep.append(i)
            best = ys[i]
    idx = np.array(keep, dtype=int)
    return Envelope(x[idx], y[idx], idx, sense)


@dataclass(frozen=True)
class FrontPoints:
    """Each distinct local optimum of a multi-start with its figures of merit.

    Attributes
    ----------
    alpha : ndarray
    label : tuple of str
        The start that found it.
    optimum : ndarray of int
        Its index among the optima of its weight (0: the weight's best).
    impulse_mps, mi, rms_obs, rms_tgt : ndarray
        Total impulse (m/s), MI of the window (nats), terminal position RMS of the observer and mean over the
        targets (km; CRLB with the process noise along the plan).
    """

    alpha: np.ndarray
    label: tuple
    optimum: np.ndarray
    impulse_mps: np.ndarray
    mi: np.ndarray
    rms_obs: np.ndarray
    rms_tgt: np.ndarray

    def envelope(self, axis: str = "rms_obs") -> Envelope:
        """Lower envelope of impulse against ``axis`` (``"rms_obs"``, ``"rms_tgt"`` or ``"mi"``)."""
        validation.choice(axis, "axis", ("rms_obs", "rms_tgt", "mi"))
        return lower_envelope(self.impulse_mps, getattr(self, axis), sense="max" if axis == "mi" else "min")

    def summary(self) -> str:
        env = set(self.envelope().index.tolist())
        lines = [f"{len(self.alpha)} distinct optima; on the lower envelope (impulse vs observer RMS): {len(env)}",
                 f"{'alpha_h':>8} {'#':>2} {'dV m/s':>9} {'MI nats':>8} {'RMS obs km':>11} {'RMS tgt km':>11} "
                 f"{'envelope':>8}  from"]
        lines += [f"{a:8.4g} {k:2d} {d:9.3f} {m:8.3f} {ro:11.2f} {rt:11.2f} {('yes' if i in env else ''):>8}  {lab}"
                  for i, (a, k, d, m, ro, rt, lab) in enumerate(zip(self.alpha, self.optimum, self.impulse_mps,
                                                                    self.mi, self.rms_obs, self.rms_tgt, self.label))]
        return "\n".join(lines)


def front_points(ms: MultiStart, scenario: wj.Scenario, k_window: int, *, others=None) -> FrontPoints:
    """Evaluate the CRLB of every distinct local optimum of ``ms`` (window-start node ``k_window``).

    ``others`` (``{alpha: plan}``, e.g. the sweep's best) adds one plan per weight the multi-start did not cover
    (labelled ``"sweep"``, optimum 0); weights of ``ms`` in it are ignored.  Points are ordered by weight."""
    validation.instance(ms, "ms", MultiStart)
    validation.instance(scenario, "scenario", wj.Scenario)
    others = {} if others is None else validation.instance(others, "others", dict, "a dict {alpha: plan}")
    reps = [(o.alpha, o.label, o.optimum, o.result) for a in ms.alphas for o in ms.optima(a)]
    for a, p in others.items():
        a = validation.real(a, "others key")
        if a not in ms.alphas and p is not None:
            reps.append((a, "sweep", 0, _checks.plan(p, f"others[{a!r}]")))
    if not reps:
        raise ValueError("ms has no converged plan")
    reps.sort(key=lambda r: (r[0], r[2]))
    k_window = validation.integer(k_window, "k_window", minimum=1, maximum=np.shape(reps[0][3].x)[0] - 2)
    mps = _mps(scenario.system)
    crlb = [wj.evaluate_crlb(scenario, r.x[k_window]).terminal_rms_km for _, _, _, r in reps]
    return FrontPoints(np.array([r[0] for r in reps]), tuple(r[1] for r in reps),
                       np.array([r[2] for r in reps], dtype=int), np.array([r[3].impulse * mps for r in reps]),
                       np.array([r[3].information for r in reps]), np.array([float(c[0]) for c in crlb]),
                       np.array([float(np.mean(c[1:])) for c in crlb]))


# --------------------------------------------------------------------------------------------------------------
# mesh study
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MeshRow:
    """The best plan at one weight on one Sundman grid: node count, start (``"figures"``: the given plan,
    ``"warm"``: the given plan interpolated onto this grid, ``"cold"``: the ballistic guess), cost, impulse (m/s),
    MI (nats), observer terminal RMS (km); ``converged`` False when neither start converged (values NaN)."""

    n_nodes: int
    alpha: float
    start: str
    converged: bool
    cost: float
    impulse_mps: float
    mi: float
    rms_km: float
    result: object


@dataclass(frozen=True)
class MeshStudy:
    """Headline weights solved on several Sundman grids.

    Attributes
    ----------
    alphas : tuple of float
    n_nodes : tuple of int
        Node counts, increasing (the figures' grid included).
    figure_nodes : int
        The node count of the plans the figures use.
    rows : tuple of MeshRow
    rtol : float
        Convergence tolerance: impulse, MI and RMS change by at most ``rtol`` (relative) between the two finest
        grids.
    attempts : tuple of tuple
        Every solve of the study, ``(n_nodes, alpha, start, cost, impulse m/s)`` with ``start`` ``"warm"`` or
        ``"cold"``; cost and impulse NaN when the solve did not converge.  Where both starts converge with different
        costs, the two are different local optima and the row keeps the lower.
    sigma : float
        Sundman exponent of the grids.
    """

    alphas: tuple
    n_nodes: tuple
    figure_nodes: int
    rows: tuple
    rtol: float
    attempts: tuple = ()
    sigma: float = 1.0

    def starts(self, alpha: float, n_nodes: int) -> dict:
        """``{start: (cost, impulse m/s)}`` of the solves at ``alpha`` on the ``n_nodes`` grid (NaN: not
        converged)."""
        return {s: (c, dv) for n, a, s, c, dv in self.attempts if n == n_nodes and a == alpha}

    def table(self, alpha: float) -> list:
        return sorted((r for r in self.rows if r.alpha == alpha), key=lambda r: r.n_nodes)

    def changes(self, alpha: float) -> dict:
        """Relative change of impulse, MI and RMS between consecutive grids whose solves converged."""
        rows = [r for r in self.table(alpha) if r.converged]
        out = {}
        for q in ("impulse_mps", "mi", "rms_km"):
            v = np.array([getattr(r, q) for r in rows])
            out[q] = np.abs(np.diff(v)) / np.abs(v[:-1])
        return out

    def finest_change(self, alpha: float) -> float:
        """Largest relative change of impulse, MI and RMS between the two finest converged grids (NaN if fewer
        than two converged)."""
        ch = self.changes(alpha)
        return float(max(c[-1] for c in ch.values())) if all(c.size for c in ch.values()) else np.nan

    def converged(self, alpha: float) -> bool:
        """Impulse, MI and RMS change by at most ``rtol`` between the two finest grids."""
        return bool(self.finest_change(alpha) <= self.rtol)

    def summary(self) -> str:
        lines = [f"mesh study: node counts {list(self.n_nodes)}; the figures use {self.figure_nodes} nodes; "
                 f"converged = impulse, MI and RMS change by at most {100 * self.rtol:g} % between the two finest "
                 "grids",
                 f"{'alpha_h':>8} {'nodes':>5} {'start':>7} {'dV m/s':>9} {'MI nats':>8} {'RMS obs km':>10} "
                 f"{'cost':>12}"]
        for a in self.alphas:
            lines += [f"{a:8.4g} {r.n_nodes:5d} {r.start:>7} {r.impulse_mps:9.3f} {r.mi:8.3f} {r.rms_km:10.2f} "
                      f"{r.cost:12.7f}" if r.converged else f"{a:8.4g} {r.n_nodes:5d}  no start converged"
                      for r in self.table(a)]
            both = [(n, st) for n in self.n_nodes if len(st := self.starts(a, n)) > 1]
            if both:
                lines.append(f"{'':8} both starts (cost, dV m/s): " + "; ".join(
                    f"{n} nodes " + ", ".join(f"{k} {c:.7f} / {dv:.1f}" if np.isfinite(c) else f"{k} failed"
                                              for k, (c, dv) in st.items()) for n, st in both))
            ch = self.changes(a)
            lines.append(f"{'':8} changes between consecutive converged grids: " + "; ".join(
                f"{q} " + ", ".join(f"{100 * v:.1f} %" for v in c) for q, c in ch.items())
                + f" -> converged: {self.converged(a)}")
        return "\n".join(lines)


def with_moved_back(solver, study: MeshStudy, back: dict) -> MeshStudy:
    """``study`` after the moved-back plans of :func:`back_to_grid` have been adopted: on the figures' grid each
    weight's row becomes its moved-back plan where that plan's cost is strictly lower (start ``"back <n>"``, ``n``
    the grid it came from), so that the table holds, per grid, the best plan known there; every moved-back solve is
    recorded in ``attempts`` (start ``"back <n>"``, NaN where it failed).

    Parameters
    ----------
    solver : ScenarioSolver
        The figures' solver (the one the study and ``back`` were made with).
    study : MeshStudy
    back : dict
        The result of :func:`back_to_grid` for ``solver`` and ``study``.
    """
    validation.instance(solver, "solver", wj.ScenarioSolver)
    validation.instance(study, "study", MeshStudy)
    back = validation.instance(back, "back", dict, "the dict of back_to_grid")
    if study.figure_nodes != solver.t.size:
        raise ValueError(f"study must be the mesh study of solver's grid ({solver.t.size} nodes); it was made on "
                         f"{study.figure_nodes}")
    sc, mps = solver.scenario, _mps(solver.scenario.system)
    rows, attempts = list(study.rows), list(study.attempts)
    for a, entry in back.items():
        if not isinstance(entry, tuple) or len(entry) != 4:
            raise validation.ArgumentTypeError(f"back[{a!r}] must be an (n_nodes, start, result, gain) tuple")
        n, _, r, _ = entry
        i = next((i for i, row in enumerate(rows) if row.alpha == a and row.n_nodes == study.figure_nodes), None)
        if i is None:
            raise ValueError(f"back holds a weight {a!r} outside the study's {study.alphas}")
        if isinstance(r, scvx.SCvxError):
            attempts.append((study.figure_nodes, a, f"back {n}", np.nan, np.nan))
            continue
        _checks.plan(r, f"back[{a!r}][2]", n=solver.t.size)
        attempts.append((study.figure_nodes, a, f"back {n}", float(r.cost), float(r.impulse * mps)))
        if r.cost < rows[i].cost:
            rows[i] = MeshRow(study.figure_nodes, a, f"back {n}", True, float(r.cost), float(r.impulse * mps),
                              float(r.information),
                              float(wj.evaluate_crlb(sc, r.x[solver.k_window]).terminal_rms_km[0]), r)
    return dataclasses.replace(study, rows=tuple(rows), attempts=tuple(attempts))


@dataclass(frozen=True)
class MeshStarts:
    """The mesh study as further starts of a multi-start (:func:`mesh_starts`).

    Attributes
    ----------
    study : MeshStudy
        The mesh study run from the multi-start's best plans, with the moved-back plans adopted on the figures' grid
        (:func:`with_moved_back`).
    back : dict
        The result of :func:`back_to_grid` (``{alpha: (n_nodes, start, result, gain)}``).
    multi : MultiStart
        The multi-start with each moved-back plan as one more start, labelled ``"mesh <n>"`` (:func:`with_starts`).
    before : dict
        ``{alpha: SCvxResult}``: the plan each weight's study started from (the best of the sweep and the generic
        starts, :func:`adopt`), against which the gains are measured.
    """

    study: MeshStudy
    back: dict
    multi: MultiStart
    before: dict

    @property
    def gains(self) -> dict:
        """``{alpha: gain}`` of every moved-back plan that converged: :math:`(J_{before} - J_{back})/(1 + |J_{before}|)`,
        positive where the mesh found a lower optimum of the figures' grid than the other starts."""
        return {a: g for a, (*_, g) in self.back.items() if np.isfinite(g)}

    @property
    def changed(self) -> list:
        """The weights whose best plan now comes from a mesh start."""
        return [a for a, lab in zip(self.multi.alphas, self.multi.best_label) if lab.startswith("mesh ")]

    def back_measurement(self) -> dict | None:
        """The measured value, shown text and note of the "generic starts find the best known plan" row (claim
        ``mesh_back`` of notebooks 05 and 06): the largest gain of a moved-back plan; None when no finer grid
        converged (nothing was moved back, the row is not judged)."""
        gains = self.gains
        if not gains:
            return None
        return dict(measured=max(gains.values()),
                    shown="; ".join(f"alpha_h {a:g}: gain {g:+.1e}" for a, g in gains.items()),
                    note="moved back from the finest grid of the mesh study, against the best of the multi-start's "
                         "generic starts; where the gain is positive the moved-back plan is adopted: the figures and "
                         "the rows above use it")

    def summary(self, mps: float) -> str:
        """The moved-back solves, the mesh table and the weights whose best plan changed (``mps``: m/s per
        velocity unit of the plans' system)."""
        mps = validation.positive(mps, "mps")
        n_fig = self.study.figure_nodes
        lines = [] if self.back else ["no mesh grid finer than the figures' converged in this run: nothing to move "
                                      "back"]
        for a, (n, start, r, g) in self.back.items():
            b = self.before[a]
            lines.append(f"alpha_h {a:g}: the {n}-node plan moved back did not converge ({r})"
                         if isinstance(r, scvx.SCvxError) else
                         f"alpha_h {a:g}: the {n}-node plan ({start} start) moved back to {n_fig} nodes: cost "
                         f"{r.cost:.8f} against the multi-start's {b.cost:.8f} (gain {g:+.2e}); "
                         f"{r.impulse * mps:.2f} against {b.impulse * mps:.2f} m/s")
        lines.append(self.study.summary())
        opts = {a: next(o for o in self.multi.at(a) if o.result is b)
                for a, b in zip(self.multi.alphas, self.multi.best) if a in self.changed}
        lines.append("best plan per weight with the mesh starts, where it changed: " + ("; ".join(
            f"alpha_h {a:g}: {o.label} ({o.impulse_mps:.2f} m/s, {o.mi:.3f} nats, cost {o.cost:.8f})"
            for a, o in opts.items()) or "nowhere"))
        return "\n".join(lines)


def mesh_starts(solver, sweep, ms: MultiStart, alphas, n_nodes, *, sigma: float = 1.0, rtol: float = 0.05,
                cold: bool = True, executor=None) -> MeshStarts:
    """The mesh study of ``alphas`` run from the best plan of ``sweep`` and ``ms`` per weight, its finest plans moved
    back onto ``solver``'s grid, and those plans added to ``ms`` as starts: :func:`adopt`, :func:`mesh_study`,
    :func:`back_to_grid`, :func:`with_starts` and :func:`with_moved_back` in that order.

    Parameters
    ----------
    solver : ScenarioSolver
        The figures' solver (the multi-start's).
    sweep : SweepResult
        The homotopy sweep on ``solver``'s grid (its weights include ``ms``'s).
    ms : MultiStart
        The multi-start of ``solver`` (generic starts).
    alphas : sequence of float
        Headline weights of the mesh study, weights of ``sweep`` with a converged plan.
    n_nodes : sequence of int
        The study's other node counts (>= 6).
    sigma, rtol, cold, executor
        As in :func:`mesh_study` (results do not depend on ``executor``).

    Returns
    -------
    MeshStarts
    """
    validation.instance(solver, "solver", wj.ScenarioSolver)
    validation.instance(sweep, "sweep", scvx.SweepResult)
    validation.instance(ms, "ms", MultiStart)
    a = validation.as_array(alphas, "alphas", ndim=(1,), min_size=1)
    provisional = adopt(sweep, ms)
    weights = [float(w) for w in sweep.alphas]
    before = {}
    for al in (float(v) for v in a):
        if al not in weights or provisional.best[weights.index(al)] is None:
            raise ValueError(f"alphas must be weights of sweep {tuple(weights)} with a converged plan; got {al!r}")
        before[al] = provisional.best[weights.index(al)]
    study = mesh_study(solver, before, n_nodes, sigma=sigma, rtol=rtol, cold=cold, executor=executor)
    back = back_to_grid(solver, study, executor=executor)
    multi = with_starts(solver, ms, {al: [(f"mesh {n}", r)] for al, (n, _, r, _) in back.items() if al in ms.alphas})
    return MeshStarts(with_moved_back(solver, study, back), back, multi, before)


def _interpolate_plan(t_from, x, u, t_to):
    """A plan moved onto another grid: states and FOH controls interpolated linearly in time."""
    return (np.stack([np.interp(t_to, t_from, x[:, j]) for j in range(6)], axis=1),
            np.stack([np.interp(t_to, t_from, u[:, j]) for j in range(3)], axis=1))


def _mesh_task(task):
    solver, alpha, x, u = task
    return _solve_task(solver, (alpha, x, u))


def mesh_study(solver, plans: dict, n_nodes, *, sigma: float = 1.0, rtol: float = 0.05, cold: bool = True,
               executor=None) -> MeshStudy:
    """Solve the weights of ``plans`` again on Sundman grids of ``n_nodes`` nodes.

    On each grid the best converged of a warm start (the given plan interpolated in time onto the grid) and, if
    ``cold``, the ballistic guess is kept.  The given plans themselves are the row of ``solver``'s grid.

    Parameters
    ----------
    solver : ScenarioSolver
        The figures' solver (its information model, keep-out and settings are used on every grid).
    plans : dict
        ``{alpha: SCvxResult}`` on ``solver``'s grid (e.g. the best of :func:`multi_start`).
    n_nodes : sequence of int
        Other node counts (>= 6).
    sigma : float
        Sundman exponent.
    rtol : float
        Convergence tolerance of :meth:`MeshStudy.converged`, in (0, 1).
    cold : bool
    executor : optional
        ``submit``-style executor for the solves (results do not depend on it).
    """
    validation.instance(solver, "solver", wj.ScenarioSolver)
    validation.instance(plans, "plans", dict, "a dict {alpha: plan}")
    if not plans:
        raise ValueError("plans must hold at least one weight")
    plans = {validation.real(a, "plans key"): _checks.plan(p, f"plans[{a!r}]", n=solver.t.size)
             for a, p in plans.items()}
    n_nodes = _checks.integers(n_nodes, "n_nodes", minimum=6)
    sigma = validation.real(sigma, "sigma")
    rtol = validation.in_range(rtol, "rtol", 0.0, 1.0, closed=False)
    cold = validation.boolean(cold, "cold")
    _checks.executor(executor)
    sc, fig_n = solver.scenario, solver.t.size
    d_km = solver.constraints[0].d_min * sc.system.length_unit_km if solver.constraints else None
    grids = {}
    for n in sorted(set(n_nodes) - {fig_n}):
        t_n, k_n, _ = sc.node_times(n, sigma)
        grids[n] = (t_n, k_n, wj.ScenarioSolver(sc, t_n, k_n, information=solver.information,
                                                keep_out=bool(solver.constraints), d_min_km=d_km,
                                                settings=solver.settings))
    tasks, where = [], []
    for n, (t_n, _, s_n) in grids.items():
        xb, ub = sc.ballistic_guess(t_n)
        for a, p in plans.items():
            tasks.append((s_n, a, *_interpolate_plan(solver.t, p.x, p.u, t_n)))
            where.append((n, a, "warm"))
            if cold:
                tasks.append((s_n, a, xb, ub))
                where.append((n, a, "cold"))
    outs = montecarlo.map_tasks(_mesh_task, tasks, executor=executor, progress=False)
    mps, rows = _mps(sc.system), []

    def row(n, a, start, r, k):
        return MeshRow(n, a, start, True, float(r.cost), float(r.impulse * mps), float(r.information),
                       float(wj.evaluate_crlb(sc, r.x[k]).terminal_rms_km[0]), r)

    for a, p in plans.items():
        rows.append(row(fig_n, a, "figures", p, solver.k_window))
        for n, (_, k_n, _) in grids.items():
            cands = [(o.cost, s, o) for (n_, a_, s), o in zip(where, outs)
                     if n_ == n and a_ == a and not isinstance(o, scvx.SCvxError)]
            if cands:
                _, s, o = min(cands, key=lambda c: c[0])
                rows.append(row(n, a, s, o, k_n))
            else:
                rows.append(MeshRow(n, a, "-", False, np.nan, np.nan, np.nan, np.nan, None))
    attempts = tuple((n_, a_, s, *((np.nan, np.nan) if isinstance(o, scvx.SCvxError) else
                                   (float(o.cost), float(o.impulse * mps))))
                     for (n_, a_, s), o in zip(where, outs))
    return MeshStudy(tuple(plans), tuple(sorted(set(n_nodes) | {fig_n})), fig_n, tuple(rows), rtol, attempts, sigma)


def back_to_grid(solver, study: MeshStudy, *, executor=None) -> dict:
    """Each weight's best plan on the finest converged grid of ``study`` (finer than the figures'), moved back onto
    ``solver``'s grid (states and first-order-hold controls interpolated in time) and solved there.

    The mesh study's grids are other starts for the figures' grid: a result with a lower cost than the figures'
    plan (``study``'s row on ``solver``'s grid) is an optimum the multi-start did not find there.  Only finer grids
    are moved back: interpolating a coarser grid's states in time can cut through a close flyby (on test case 2 a
    12-node plan moved onto 16 nodes starts inside the Moon).

    Parameters
    ----------
    solver : ScenarioSolver
        The figures' solver (the one :func:`mesh_study` was given).
    study : MeshStudy
        Its mesh study.
    executor : optional
        ``submit``-style executor (results do not depend on it).

    Returns
    -------
    dict
        ``{alpha: (n_nodes, start, result, gain)}``: the grid and start the plan came from, the
        :class:`~cislunar.guidance.scvx.SCvxResult` on ``solver``'s grid (or the :class:`SCvxError` of a solve that
        did not converge, gain NaN), and the gain :math:`(J_{fig} - J)/(1 + |J_{fig}|)` over the figures' plan (the
        measure of :class:`MultiStart`'s ``cost_tol``); weights without a finer converged grid are left out.
    """
    validation.instance(solver, "solver", wj.ScenarioSolver)
    validation.instance(study, "study", MeshStudy)
    if study.figure_nodes != solver.t.size:
        raise ValueError(f"study must be the mesh study of solver's grid ({solver.t.size} nodes); it was made on "
                         f"{study.figure_nodes}")
    _checks.executor(executor)
    picks = {}
    for a in study.alphas:
        others = [r for r in study.table(a) if r.converged and r.n_nodes > study.figure_nodes]
        if others:
            picks[a] = others[-1]
    tasks = []
    for a, r in picks.items():
        t_n = solver.scenario.node_times(r.n_nodes, study.sigma)[0]
        tasks.append((solver, a, *_interpolate_plan(t_n, r.result.x, r.result.u, solver.t)))
    outs = montecarlo.map_tasks(_mesh_task, tasks, executor=executor, progress=False)
    fig = {a: next(r.cost for r in study.table(a) if r.n_nodes == study.figure_nodes) for a in picks}
    return {a: (r.n_nodes, r.start, o, np.nan if isinstance(o, scvx.SCvxError) else
                (fig[a] - float(o.cost)) / (1 + abs(fig[a])))
            for (a, r), o in zip(picks.items(), outs)}

r"""How large are Wolf & Jones' test-case-1 plans?  A sweep over the readings the paper leaves open (issue 22, item 2).

The question
------------
Eq. 42 weighs the control term against the mutual information, :math:`(1-\alpha_h)\,\mathrm{control} -
\alpha_h\mathcal I`, but the paper says neither how the control term is normalised (LU/TU, km/s or m/s; total
impulse, or an average per node or per day, as Fig. 5's axis label "average impulse" suggests) nor how Table 3's
"Q [km/s^3] = 1e-11" is to be read.  Both set how much impulse a nat of information is worth, and therefore how far
the plan of a given :math:`\alpha_h` swings away from the reference DRO.  With the adopted readings (total impulse in
LU/TU, :math:`q = 10^{-11}` LU^2/TU^3) the :math:`\alpha_h = 2\times10^{-2}` plan spends about 100 m/s and swings far
from the DRO, while the paper writes of Fig. 1 that the departure is "not immediately apparent".

:func:`plan_size_sweep` solves test case 1 at :math:`\alpha_h = 5\times10^{-3}` and :math:`2\times10^{-2}` (each from
the ballistic DRO, as in the notebook's cold starts) for every combination of a control-term normalisation
(:data:`NORMALISATIONS`, through :class:`cislunar.papers.wolf_jones.scenarios.ScenarioSolver`'s ``control_unit`` and
``control_average``) and a process-noise reading
(:data:`cislunar.papers.wolf_jones.scenarios.PROCESS_NOISE_READINGS_KM2_S3`: the literal unit fix and three small
readings), and reports per combination the impulse (m/s), the MI (nats), the largest departure from the reference
DRO (km) and the largest distance from the Moon (km); the minimum-impulse plan (:math:`\alpha_h = 0`, the same for
every combination) is solved once for comparison.

"Not immediately apparent", fixed before any sweep was run
----------------------------------------------------------
Fig. 1 draws the whole reference DRO in the rotating frame, so its scale is the DRO's size: we take the DRO's
largest distance from the Moon, :math:`R_{DRO}` (117,553 km for test case 1's corrected observer DRO).  A
departure is "not immediately apparent" on such a panel when it is a small fraction of that scale: we fix
:data:`FIT_FRACTION` = 5 %, i.e. a largest departure from the reference DRO of at most :math:`0.05 R_{DRO}`
(about 5,900 km, a few line widths on a printed panel), **at both weights**.  A combination *fits the text* when,
in addition, the paper's qualitative statements about Figs. 1-3 hold: "the right trajectory departs from the
reference to a higher degree than the left" (departure at :math:`2\times10^{-2}` larger than at
:math:`5\times10^{-3}`) and "increasing the homotopy accumulates a higher total impulse" (impulse larger at
:math:`2\times10^{-2}`), with both solves converged.  These criteria and the 5 % were written here before the sweep
was first run; the sweep's numbers were not looked at to choose them.  The closing-table row built on the
result (``claims/plan_size.py``) is "consistent (tuned)" if a normalisation other than the adopted one is needed
to fit: that normalisation would then be chosen by looking at Fig. 1's text.

Units: impulses in m/s, distances in km, MI in nats; states are rotating-frame barycentric CR3BP states in LU and
LU/TU.  Every solve is deterministic, so the result does not depend on the executor.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from cislunar.cr3bp.propagation import ImpactError, propagate
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.sensing import covariance as cov
from cislunar.utils import montecarlo, validation

__all__ = ["NORMALISATIONS", "ADOPTED_NORMALISATION", "ADOPTED_READING", "LITERAL_READING", "FIT_FRACTION",
           "PAPER_ALPHAS", "PlanSizeRow", "PlanSizeStudy", "q_reading_nd", "dro_size_km", "plan_size_sweep"]

#: Readings of Eq. 42's control term: label -> (``control_unit``, ``control_average``) of ScenarioSolver.  The total
#: in km/s differs from the adopted total in LU/TU by the factor 1.0245 only, so it is not swept.
NORMALISATIONS = {
    "total, LU/TU (adopted)": ("LU/TU", "total"),
    "total, m/s": ("m/s", "total"),
    "per node, LU/TU": ("LU/TU", "node"),
    "per node, m/s": ("m/s", "node"),
    "per day, km/s": ("km/s", "day"),
    "per day, m/s": ("m/s", "day"),
}
ADOPTED_NORMALISATION = "total, LU/TU (adopted)"
ADOPTED_READING = "1e-11 LU^2/TU^3 (normalised units, adopted)"
LITERAL_READING = "1e-11 km^2/s^3 (unit label missing a square)"
#: Largest departure from the reference DRO, as a fraction of the DRO's largest distance from the Moon, that is
#: "not immediately apparent" on Fig. 1 (fixed before the sweep was run; module docstring).
FIT_FRACTION = 0.05
#: The weights of Fig. 1 (left, right).
PAPER_ALPHAS = (5e-3, 2e-2)


def q_reading_nd(reading: str, system) -> float:
    """Acceleration PSD of a process-noise reading (a key of ``PROCESS_NOISE_READINGS_KM2_S3``), LU^2/TU^3."""
    reading = validation.choice(reading, "reading", tuple(wj.PROCESS_NOISE_READINGS_KM2_S3))
    return _q_nd(reading, system)


def _q_nd(reading: str, system) -> float:

    return float(cov.psd_to_nondimensional(wj.PROCESS_NOISE_READINGS_KM2_S3[reading], system))


def dro_size_km(scenario: wj.Scenario, n: int = 2000) -> float:
    """Largest distance from the Moon (km) of the observer's reference DRO over one period (``n`` samples)."""
    validation.instance(scenario, "scenario", wj.Scenario)
    n = validation.integer(n, "n", minimum=10)
    return _dro_size_km(scenario, n)


def _dro_size_km(sc: wj.Scenario, n: int) -> float:

    x = propagate(sc.system, sc.observer_x0, np.linspace(0.0, sc.period, n)).x
    return float(np.max(_moon_distance_km(sc, x)))


def _moon_distance_km(sc: wj.Scenario, x) -> np.ndarray:

    moon = np.array([1.0 - sc.system.mu, 0.0, 0.0])
    return np.linalg.norm(x[:, :3] - moon, axis=1) * sc.system.length_unit_km


@dataclass(frozen=True)
class PlanSizeRow:
    """One solve of the sweep.

    Attributes
    ----------
    normalisation, reading : str
        Keys of :data:`NORMALISATIONS` and ``PROCESS_NOISE_READINGS_KM2_S3``.
    control_scale : float
        :math:`c` of the control term (:func:`cislunar.papers.wolf_jones.scenarios.control_scale`).
    q : float
        Acceleration PSD used by the information model, LU^2/TU^3.
    alpha : float
        :math:`\\alpha_h`.
    converged : bool
    impulse_mps, mi_nats, departure_km, moon_distance_km : float
        Total impulse (m/s), window MI (nats, planning model), largest distance from the reference DRO (km) and
        largest distance from the Moon (km) of the single-shooting re-flight; NaN when the solve failed.
    iterations : int
    error : str
        Why the solve failed ('' when it converged).
    cpu_seconds : float
        CPU time of the solve and re-flight in the thread that ran it (excluded from equality: it differs between
        runs).
    """

    normalisation: str
    reading: str
    control_scale: float
    q: float
    alpha: float
    converged: bool
    impulse_mps: float
    mi_nats: float
    departure_km: float
    moon_distance_km: float
    iterations: int
    error: str
    cpu_seconds: float = field(default=0.0, compare=False)


@dataclass(frozen=True)
class PlanSizeStudy:
    """Result of :func:`plan_size_sweep`.

    Attributes
    ----------
    rows : tuple of PlanSizeRow
        Every solve, in task order (normalisation-major, then reading, then alpha).
    baseline : PlanSizeRow
        The minimum-impulse plan (:math:`\\alpha_h = 0`; the same for every combination).
    normalisations, readings : tuple of str
    alphas : tuple of float
    n_nodes : int
    dro_size_km : float
        :math:`R_{DRO}`, the reference DRO's largest distance from the Moon, km.
    fraction : float
        :data:`FIT_FRACTION` used.
    seconds : float
        Wall time of the sweep.
    """

    rows: tuple
    baseline: PlanSizeRow
    normalisations: tuple
    readings: tuple
    alphas: tuple
    n_nodes: int
    dro_size_km: float
    fraction: float
    seconds: float

    @property
    def threshold_km(self) -> float:
        """Largest departure that is "not immediately apparent": ``fraction`` times :attr:`dro_size_km`, km."""
        return self.fraction * self.dro_size_km

    def row(self, normalisation: str, reading: str, alpha: float) -> PlanSizeRow:
        """The row of one combination and weight."""
        for r in self.rows:
            if r.normalisation == normalisation and r.reading == reading and r.alpha == alpha:
                return r
        raise ValueError(f"no row for normalisation={normalisation!r}, reading={reading!r}, alpha={alpha!r}")

    def small(self, normalisation: str, reading: str) -> bool:
        """Every weight converged with a largest departure at most :attr:`threshold_km`."""
        rows = [self.row(normalisation, reading, a) for a in self.alphas]
        return all(r.converged and r.departure_km <= self.threshold_km for r in rows)

    def qualitative(self, normalisation: str, reading: str) -> bool:
        """Departure and impulse both larger at the largest weight than at the smallest (Figs. 1-3's text)."""
        lo, hi = (self.row(normalisation, reading, a) for a in (min(self.alphas), max(self.alphas)))
        return bool(lo.converged and hi.converged and hi.departure_km > lo.departure_km
                    and hi.impulse_mps > lo.impulse_mps)

    def fits(self, normalisation: str, reading: str) -> bool:
        """"Not immediately apparent" at every weight and the qualitative statements hold."""
        return self.small(normalisation, reading) and self.qualitative(normalisation, reading)

    @property
    def fitting(self) -> list:
        """``(normalisation, reading)`` of every combination that fits the text."""
        return [(n, q) for n in self.normalisations for q in self.readings if self.fits(n, q)]

    def departures(self, alpha: float) -> np.ndarray:
        """Largest departures (km), shape (normalisations, readings), at one weight (NaN where a solve failed)."""
        return np.array([[self.row(n, q, alpha).departure_km for q in self.readings] for n in self.normalisations])

    def summary(self) -> str:
        """A table of every solve and the combinations that fit."""
        b = self.baseline
        lines = [f"{self.n_nodes} nodes; reference DRO reaches {self.dro_size_km:,.0f} km from the Moon; "
                 f"'not immediately apparent': departure <= {100 * self.fraction:g} % of it = "
                 f"{self.threshold_km:,.0f} km at every weight",
                 f"alpha_h = 0 (every combination): {b.impulse_mps:.2f} m/s, departure {b.departure_km:,.0f} km, "
                 f"Moon distance up to {b.moon_distance_km:,.0f} km",
                 f"{'normalisation':<24} {'c':>9} {'process noise':<46} {'alpha_h':>7} {'m/s':>8} {'MI':>7} "
                 f"{'departure km':>13} {'Moon km':>9}"]
        for r in self.rows:
            if r.converged:
                lines.append(f"{r.normalisation:<24} {r.control_scale:9.3g} {r.reading:<46} {r.alpha:7.0e} "
                             f"{r.impulse_mps:8.2f} {r.mi_nats:7.2f} {r.departure_km:13,.0f} "
                             f"{r.moon_distance_km:9,.0f}")
            else:
                lines.append(f"{r.normalisation:<24} {r.control_scale:9.3g} {r.reading:<46} {r.alpha:7.0e} "
                             f"failed: {r.error[:50]}")
        fit = self.fitting
        lines.append("fit the text at every weight: " + ("; ".join(f"{n} / {q}" for n, q in fit) if fit else "none"))
        cpu = sum(r.cpu_seconds for r in self.rows) + self.baseline.cpu_seconds
        lines.append(f"{len(self.rows) + 1} solves, {self.seconds:.0f} s wall, {cpu:.0f} s CPU in the solving threads")
        return "\n".join(lines)


def _row(sc, solver, norm, reading, alpha, cpu0, res=None, error="", iterations=0) -> PlanSizeRow:

    mps = sc.system.velocity_unit_km_s * 1e3
    if res is None:
        nan = float("nan")
        return PlanSizeRow(norm, reading, solver.control_scale, sc.q, float(alpha), False, nan, nan, nan, nan,
                           int(iterations), error, time.thread_time() - cpu0)
    tf, xf = wj.fly(sc, solver.t, res.u, refine=10)
    ref = propagate(sc.system, sc.observer_x0, tf).x
    dep = float(np.max(np.linalg.norm(xf[:, :3] - ref[:, :3], axis=1))) * sc.system.length_unit_km
    return PlanSizeRow(norm, reading, solver.control_scale, sc.q, float(alpha), True, float(res.impulse * mps),
                       float(res.information), dep, float(np.max(_moon_distance_km(sc, xf))), res.iterations, "",
                       time.thread_time() - cpu0)


def _combination(problem: tuple, task: tuple) -> list:
    """Solve one (normalisation, reading) combination at every weight of ``task``, each from the ballistic DRO."""

    sc0, t, k_ws, forward_hessian, settings = problem
    norm, reading, alphas, known = task
    sc = dataclasses.replace(sc0, q=_q_nd(reading, sc0.system))
    info = sc.information_model()
    if forward_hessian:
        info.hessian_scheme = "forward"
    unit, average = NORMALISATIONS[norm]
    solver = wj.ScenarioSolver(sc, t, k_ws, information=info, settings=settings, control_unit=unit,
                               control_average=average)
    x_ball, u_ball = sc.ballistic_guess(t)
    rows = []
    for a in alphas:
        cpu0 = time.thread_time()
        if a in known:  # already solved from the ballistic DRO (plan_size_sweep's known)
            rows.append(_row(sc, solver, norm, reading, a, cpu0, known[a]))
            continue
        try:
            res = solver(a, x_ball, u_ball)
        except scvx.SCvxError as exc:
            rows.append(_row(sc, solver, norm, reading, a, cpu0, error=exc.reason, iterations=len(exc.history)))
            continue
        except ImpactError as exc:  # an iterate so far off that its window arc hits the Moon: no plan
            rows.append(_row(sc, solver, norm, reading, a, cpu0, error=f"an SCvx iterate hit the Moon ({exc})"))
            continue
        rows.append(_row(sc, solver, norm, reading, a, cpu0, res))
    return rows


class _Task:
    """Picklable ``task -> _combination(problem, task)``."""

    def __init__(self, problem):
        self.problem = problem

    def __call__(self, task):
        return _combination(self.problem, task)


def plan_size_sweep(n_nodes: int, *, normalisations=None, readings=None, alphas=PAPER_ALPHAS, sigma: float = 1.0,
                    forward_hessian: bool = False, settings=None, fraction: float = FIT_FRACTION, executor=None,
                    progress: bool = False, known=None) -> PlanSizeStudy:
    """Test case 1 at each weight for every control-term normalisation and process-noise reading.

    Parameters
    ----------
    n_nodes : int
        Sundman-spaced nodes (notebook 05: 40 full, 18 quick).
    normalisations : sequence of str, optional
        Keys of :data:`NORMALISATIONS` (default: all).
    readings : sequence of str, optional
        Keys of ``PROCESS_NOISE_READINGS_KM2_S3`` (default: all four).
    alphas : sequence of float
        Strictly increasing weights in (0, 1] (default: Fig. 1's 5e-3 and 2e-2).
    sigma : float
        Sundman exponent.
    forward_hessian : bool
        Forward-difference Hessian of the MI (half the cost; shapes only the trust-region model).
    settings : cislunar.guidance.scvx.SCvxSettings, optional
    fraction : float
        Largest departure, as a fraction of the DRO's largest Moon distance, that is "not immediately apparent"
        (default :data:`FIT_FRACTION`, fixed before the sweep was run).
    executor : concurrent.futures.Executor or dask.distributed.Client, optional
        Runs the combinations side by side (one task each); the result is bit-identical to the serial one.
    progress : bool
    known : dict, optional
        ``{alpha: SCvxResult}``: plans of the adopted normalisation and reading already solved from the ballistic
        DRO on this grid with the same ``forward_hessian`` and ``settings`` (e.g. notebook 05's sweep at
        alpha_h = 0 and its multi-start's ballistic starts); used instead of solving them again (SCvx is
        deterministic: the same plans, bit for bit, apart from the run times in the rows).

    Returns
    -------
    PlanSizeStudy
    """
    n_nodes = validation.integer(n_nodes, "n_nodes", minimum=6)
    norms = tuple(NORMALISATIONS) if normalisations is None else tuple(
        validation.choice(v, "normalisations", tuple(NORMALISATIONS)) for v in _sequence(normalisations,
                                                                                        "normalisations"))
    reads = tuple(wj.PROCESS_NOISE_READINGS_KM2_S3) if readings is None else tuple(
        validation.choice(v, "readings", tuple(wj.PROCESS_NOISE_READINGS_KM2_S3)) for v in _sequence(readings,
                                                                                                    "readings"))
    a = validation.as_array(alphas, "alphas", ndim=(1,), min_size=1)
    if a[0] <= 0 or a[-1] > 1 or np.any(np.diff(a) <= 0):
        raise ValueError(f"alphas must be strictly increasing within (0, 1]; got {a}")
    alphas = tuple(float(v) for v in a)
    sigma = validation.real(sigma, "sigma")
    forward_hessian = validation.boolean(forward_hessian, "forward_hessian")
    if settings is not None:
        validation.instance(settings, "settings", scvx.SCvxSettings)
    fraction = validation.in_range(fraction, "fraction", 0.0, 1.0, closed=False)
    progress = validation.boolean(progress, "progress")
    if executor is not None and not callable(getattr(executor, "submit", None)):
        raise ValueError(f"executor must have a submit method; got {type(executor).__name__}")

    sc = wj.test_case_1()
    t, k_ws, _ = sc.node_times(n_nodes, sigma)
    known = {} if known is None else validation.instance(known, "known", dict, "a dict {alpha: SCvxResult}")
    for k, r in known.items():
        validation.instance(r, f"known[{k!r}]", scvx.SCvxResult)
        if r.alpha != validation.real(k, "known key") or not np.array_equal(r.t, t):
            raise ValueError(f"known[{k!r}] must be solved at alpha = {k!r} on the {t.size}-node grid; got alpha = "
                             f"{r.alpha:g} on {np.size(r.t)} nodes")
    adopted = {float(k): r for k, r in known.items()}
    task = _Task((sc, t, k_ws, forward_hessian, settings))
    tasks = [(ADOPTED_NORMALISATION, ADOPTED_READING, (0.0,), adopted)] + [
        (n, q, alphas, adopted if (n, q) == (ADOPTED_NORMALISATION, ADOPTED_READING) else {}) for n in norms
        for q in reads]
    t0 = time.perf_counter()
    out = montecarlo.map_tasks(task, tasks, executor=executor, progress=progress, desc="plan size")
    seconds = time.perf_counter() - t0
    rows = tuple(r for chunk in out[1:] for r in chunk)
    return PlanSizeStudy(rows, out[0][0], norms, reads, alphas, int(t.size), _dro_size_km(sc, 2000), fraction,
                         seconds)


def _sequence(value, name: str) -> list:

    if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        raise validation.ArgumentTypeError(f"{name} must be a sequence of str; got {type(value).__name__}")
    out = list(value)
    if not out:
        raise ValueError(f"{name} must not be empty")
    return out

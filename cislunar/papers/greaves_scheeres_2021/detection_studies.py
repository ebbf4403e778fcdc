"""Studies and aggregations of notebook 10 (Greaves & Scheeres 2021, "Maneuver Detection", Tables 5-8): the tuning
map of the unstated window weight and its two readings (:func:`run_tuning_map`), the single run of Figs. 10-13 under
both tunings with its readout (:func:`run_tuning_demo`), the Monte Carlo studies of Sections 2-6, and the standard
errors behind the closing table's Monte Carlo tolerances.

The tolerances of the Monte Carlo comparisons are standard errors passed to
:meth:`cislunar.publish.claims.Claim.judge` with the claims of
:mod:`cislunar.papers.greaves_scheeres_2021.claims.maneuver_detection`; this module computes them.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy import stats

from cislunar.cr3bp.dynamics import check_system
from cislunar.cr3bp.orbits import PeriodicOrbit
from cislunar.estimation import adaptive_ocbe as ad
from cislunar.estimation.batched_ocbe import BatchOCBEResult
from cislunar.estimation.consistency import NEES_PROBABILITY, nees, nees_limit
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021 import panels as ocbe_panels
from cislunar.papers.greaves_scheeres_2021 import tracking
from cislunar.papers.greaves_scheeres_2021.claims.maneuver_detection import (
    CLAIMS,
    HEALTH_NEES_DIVERGED,
    HEALTH_PLAUSIBLE_FLOOR,
    HEALTH_RESIDUAL_BENIGN,
    PAPER_ACCURACY,
    PAPER_ZLIM,
    STABLE_MARGIN,
)
from cislunar.utils import montecarlo, validation

__all__ = ["accuracy_standard_error", "accuracy_comparison_standard_error", "accuracy_exact_text", "PAPER_TEST_RUNS",
           "PAPER_TRAINING_RUNS", "paper_threshold_standard_error", "threshold_comparison_standard_error",
           "one_run_comparison_standard_error", "fraction_standard_error", "ACCURACY_DIGIT_TOL", "improvement_in_standard_errors",
           "finite_or", "CONSISTENT_FRACTION",
           "TuningMap", "run_tuning_map", "TuningDemo", "run_tuning_demo", "SpikeStudy", "run_spike_study", "TAGS", "ratio_text",
           "TrainingStudies", "run_training_studies", "DIRECTIONS", "PmJSearch", "run_pm_j_search", "BurnZStudy",
           "run_burn_z_study", "lead_report", "lead_reading", "JOINT_ZLIM_TOL", "JOINT_SCREEN_ZLIM_TOL",
           "JointSearch", "run_joint_search", "LeadGrid", "run_lead_grid", "HealthRuns", "closing_rows"]


def _check_setup(setup, name: str = "setup") -> det.DetectionSetup:
    return validation.instance(setup, name, det.DetectionSetup, "a detection.DetectionSetup (detection.make_setup)")


def _check_orbit(orbit, name: str = "orbit") -> PeriodicOrbit:
    return validation.instance(orbit, name, PeriodicOrbit, "a cislunar.cr3bp.orbits.PeriodicOrbit")


def _check_executor(executor):
    """``None`` (serial) or an object with a ``submit`` method (a concurrent.futures executor, a Dask Client)."""
    if executor is not None and not callable(getattr(executor, "submit", None)):
        raise validation.ArgumentTypeError(f"executor must be None or have a submit(fn, *args) method (a "
                                           f"concurrent.futures executor or a Dask Client); got "
                                           f"{type(executor).__name__}")


def _setup_maker(system):
    """:func:`detection.make_setup` (default cadence, period and sub-grid) building one scenario per orbit and angle
    noise: the tunings of a track share its propagation and event search, and every setup equals the one
    ``make_setup`` builds call by call."""
    scenarios = {}  # (id(orbit), noise) -> (orbit, first setup); the orbit is kept so that its id stays its own

    def make(orbit, q_window_km2_s3, q_base_km2_s3, *, window_hours, sigma_angle_rad=tracking.DEFAULT_SIGMA_ANGLE_RAD):
        key = (id(orbit), float(sigma_angle_rad))
        if key not in scenarios:
            st = det.make_setup(system, orbit, q_window_km2_s3, q_base_km2_s3, window_hours=window_hours,
                                sigma_angle_rad=sigma_angle_rad)
            scenarios[key] = (orbit, st)
            return st
        st = scenarios[key][1]
        return det._retuned(st.scenario, validation.positive(q_window_km2_s3, "q_window_km2_s3"),
                            validation.positive(q_base_km2_s3, "q_base_km2_s3"),
                            validation.positive(window_hours, "window_hours"), st.n_sub, st.tol)

    return make


def _positive_values(value, name: str) -> np.ndarray:
    """A non-empty 1-D array of positive finite numbers (a set is taken in sorted order)."""
    if isinstance(value, (set, frozenset)):
        value = sorted(value)
    v = validation.as_array(value, name, ndim=(1,), min_size=1)
    if np.any(v <= 0):
        raise ValueError(f"{name} must hold positive values; got {v}")
    return v


#: Half a unit of the last digit the paper prints a detection accuracy with (whole percent, Table 7).
ACCURACY_DIGIT_TOL = 0.005


def accuracy_standard_error(paper: float, n: int) -> float:
    """Standard error of a detection accuracy over ``n`` test runs: binomial, at the end of the paper's printed
    interval (``paper`` +- :data:`ACCURACY_DIGIT_TOL`, clipped to [0, 1]) nearer one half, where it is largest.

    The Table 7 tolerance, fixed before comparing, is :data:`ACCURACY_DIGIT_TOL` (the printed digits) plus two of
    these: e.g. 100 % over 200 runs: 0.5 + 2 x 0.50 = 1.5 points; 97 %: 0.5 + 2 x 1.30 = 3.1 points.  (It
    replaces a rule with a floor of one point per standard error, whose 2-point tolerance had no basis at 100 %.)
    """
    p = validation.real(paper, "paper")
    if not 0.0 <= p <= 1.0:
        raise ValueError(f"paper must be a rate in [0, 1]; got {paper!r}")
    n = validation.integer(n, "n", minimum=1)
    edge = min(1.0, p + ACCURACY_DIGIT_TOL) if p < 0.5 else max(0.0, p - ACCURACY_DIGIT_TOL)
    return float(np.sqrt(edge * (1 - edge) / n))


#: Test runs per policy behind each accuracy of the paper's Table 7 (100 without and 100 with a maneuver).
PAPER_TEST_RUNS = 200


def accuracy_comparison_standard_error(paper: float, n: int, n_paper: int = PAPER_TEST_RUNS) -> float:
    """Standard error of the difference between our detection accuracy over ``n`` test runs and the paper's over
    ``n_paper``: the two binomial errors (:func:`accuracy_standard_error`, each at the end of the paper's printed
    interval nearer one half) in quadrature.  Both accuracies are Monte Carlo estimates, so the Table 7 tolerance is
    :data:`ACCURACY_DIGIT_TOL` plus two of these (e.g. 100 % over 200 and 200 runs: 0.5 + 2 x 0.71 = 1.9 points)."""
    se = accuracy_standard_error(paper, n)
    n_paper = validation.integer(n_paper, "n_paper", minimum=1)
    return float(np.hypot(se, accuracy_standard_error(paper, n_paper)))


#: Training runs behind each threshold of Eq. 35 ("Maneuver Detection": 500 without and 3000 with a maneuver).
PAPER_TRAINING_RUNS = (500, 3000)


def paper_threshold_standard_error(se: float, z_lim: float, paper: float, n_h0: int, n_h1: int) -> float:
    r"""Estimated Monte Carlo standard error of the paper's own threshold (Eq. 35), m/s like the inputs.

    The paper's :math:`z_{lim}` comes from a finite Monte Carlo (:data:`PAPER_TRAINING_RUNS`) and so has a sampling
    error of its own, which it does not print.  We estimate it from our bootstrap: our relative standard error
    ``se / z_lim`` (a threshold's spread scales with the spread of the z distributions, i.e. with z itself), at the
    paper's value, scaled from our training sizes ``n_h0``, ``n_h1`` to the paper's by ``(n_ours / n_paper)**0.4``
    (the larger of the two ratios: the threshold's variance is a sum of one term per sample; a kernel density
    estimate with Scott's bandwidth :math:`h \propto n^{-1/5}` has a variance :math:`\propto 1/(n h) \propto
    n^{-4/5}`, so its spread falls as :math:`n^{-2/5}`, slower than :math:`n^{-1/2}`).  With the paper's sizes (the
    full run's) this is ``se * |paper| / z_lim``.

    Parameters
    ----------
    se : float
        Our bootstrap standard error of z_lim (>= 0).
    z_lim : float
        Our threshold (> 0).
    paper : float
        The paper's threshold (> 0), in the units of ``z_lim``.
    n_h0, n_h1 : int
        Our training runs without and with a maneuver.
    """
    se = validation.positive(se, "se", allow_zero=True)
    z_lim = validation.positive(z_lim, "z_lim")
    paper = validation.positive(paper, "paper")
    n_h0 = validation.integer(n_h0, "n_h0", minimum=1)
    n_h1 = validation.integer(n_h1, "n_h1", minimum=1)
    ratio = max(n_h0 / PAPER_TRAINING_RUNS[0], n_h1 / PAPER_TRAINING_RUNS[1])
    return float(se / z_lim * paper * ratio ** 0.4)


def threshold_comparison_standard_error(se: float, z_lim: float, paper: float, n_h0: int, n_h1: int) -> float:
    """Standard error of the difference between our threshold and the paper's: our bootstrap standard error ``se``
    and the paper's (:func:`paper_threshold_standard_error`) in quadrature.  The z_lim rows' tolerance, fixed before
    comparing, is half the paper's last printed digit plus two of these."""
    return float(np.hypot(validation.positive(se, "se", allow_zero=True),
                          paper_threshold_standard_error(se, z_lim, paper, n_h0, n_h1)))


def one_run_comparison_standard_error(sd: float, n: int) -> float:
    """Standard error of the difference between the paper's single run and our mean over ``n`` runs of the same
    experiment, ``sd`` their single-run standard deviation: ``sd * sqrt(1 + 1/n)`` (the paper's run spreads by one
    ``sd``, our mean by ``sd / sqrt(n)``).  The Fig. 22 z rows' tolerance is half the paper's last printed digit
    plus two of these."""
    sd = validation.positive(sd, "sd", allow_zero=True)
    n = validation.integer(n, "n", minimum=1)
    return float(sd * np.sqrt(1.0 + 1.0 / n))


def accuracy_exact_text(accuracy: float, paper: float, n: int) -> str:
    """Exact tests of an accuracy over ``n`` test runs against the paper's (a check of the normal-approximation
    tolerance, which is poor near 100 %): the one-sided binomial probability of at least our number of errors if the
    true accuracy were at the end of the paper's printed interval (``paper`` - :data:`ACCURACY_DIGIT_TOL`), and
    Fisher's exact two-sided p-value of our counts against the paper's own :data:`PAPER_TEST_RUNS` test runs."""
    a = validation.in_range(accuracy, "accuracy", 0.0, 1.0)
    p = validation.in_range(paper, "paper", 0.0, 1.0)
    n = validation.integer(n, "n", minimum=1)
    k = int(round((1 - a) * n))
    k_paper = int(round((1 - p) * PAPER_TEST_RUNS))
    edge = min(1.0, 1 - p + ACCURACY_DIGIT_TOL)
    p_bin = float(stats.binom.sf(k - 1, n, edge)) if k > 0 else 1.0
    p_fisher = float(stats.fisher_exact([[n - k, k], [PAPER_TEST_RUNS - k_paper, k_paper]]).pvalue)
    return (f"{k} errors; exact binomial P(>= {k} errors | accuracy {100 * (1 - edge):.1f} %) = {p_bin:.3f}; Fisher "
            f"exact against the paper's {PAPER_TEST_RUNS - k_paper}/{PAPER_TEST_RUNS}: p = {p_fisher:.2f}")


def fraction_standard_error(fraction: float, n: int) -> float:
    """Binomial standard error of a fraction of ``n`` Monte Carlo runs, evaluated at the criterion's ``fraction``."""
    f = validation.real(fraction, "fraction")
    if not 0.0 <= f <= 1.0:
        raise ValueError(f"fraction must be in [0, 1]; got {fraction!r}")
    return float(np.sqrt(f * (1 - f) / validation.integer(n, "n", minimum=1)))


def improvement_in_standard_errors(error: float, reference: float, se_error: float, se_reference: float) -> float:
    """How much lower ``error`` is than ``reference``, in combined standard errors
    :math:`(e_{ref} - e)/\\sqrt{s_e^2 + s_{ref}^2}` (0 when both standard errors vanish and the two are equal;
    +-1e12 when they vanish and the two differ)."""
    d = validation.real(reference, "reference") - validation.real(error, "error")
    s = float(np.hypot(validation.positive(se_error, "se_error", allow_zero=True),
                       validation.positive(se_reference, "se_reference", allow_zero=True)))
    if s == 0.0:
        return 0.0 if d == 0 else float(np.sign(d)) * 1e12
    return d / s


def finite_or(value: float, fallback: float) -> float:
    """``value`` if it is a finite number, else ``fallback`` (a ratio that could not be formed)."""
    v = validation.real(value, "value", finite=False)
    fallback = validation.real(fallback, "fallback")
    return v if np.isfinite(v) else fallback


# ---------------------------------------------------------------------------------------------------------------
# The tuning map (notebook 10, Section 2)
# ---------------------------------------------------------------------------------------------------------------

#: Largest fraction of NEES-inconsistent runs per cell for a setting to count as consistent (notebook 09's flag).
CONSISTENT_FRACTION = 0.10


@dataclass(frozen=True)
class TuningMap:
    """Reduced Monte Carlo per (orbit, policy, window factor f, setting) of the window tuning.

    Attributes
    ----------
    cells : dict
        ``(orbit, policy, f, setting)`` -> dict with ``z_lim`` [m/s], ``err`` (FP + MD), ``h0``/``h1`` (fractions of
        inconsistent runs, forward and smoothed), ``n`` (H0, H1 runs) and ``slope`` (z against the magnitude).
    orbits, policies : tuple of str
    variants : tuple of str
        Settings; the first is the base (paper's window, our noise and base weight), swept over ``f_grid`` on every
        orbit; the others over ``f_side`` on the 9:2 NRHO.
    f_grid, f_side : tuple of float
    paper_zlim : dict
        Policy -> the paper's threshold, m/s.
    """

    cells: dict
    orbits: tuple
    policies: tuple
    variants: tuple
    f_grid: tuple
    f_side: tuple
    paper_zlim: dict

    @property
    def base(self) -> str:
        return self.variants[0]

    def factors(self, variant: str) -> tuple:
        return self.f_grid if variant == self.base else self.f_side

    def worst(self, orbit, policy, f, variant=None) -> float:
        """Largest fraction of inconsistent runs over hypotheses and passes of one cell."""
        c = self.cells[orbit, policy, f, self.base if variant is None else variant]
        return max(*c["h0"], *c["h1"])

    def consistent_on(self, orbit, f, variant) -> bool:
        return all(self.worst(orbit, p, f, variant) <= CONSISTENT_FRACTION for p in self.policies)

    @property
    def consistent_factors(self) -> list:
        """Factors of the grid at which every orbit, policy and hypothesis is consistent (base setting)."""
        return [f for f in self.f_grid if all(self.consistent_on(o, f, self.base) for o in self.orbits)]

    @property
    def f_c(self) -> float:
        """The consistency reading: the smallest consistent factor (the largest of the grid if none is)."""
        return self.consistent_factors[0] if self.consistent_factors else self.f_grid[-1]

    def f_match(self, policy, variant=None) -> float:
        """Factor at which the 9:2 NRHO's z_lim equals the paper's (log-log interpolation; NaN outside the grid)."""
        v = self.base if variant is None else variant
        fs = self.factors(v)
        zl = np.array([self.cells["9:2 NRHO", policy, f, v]["z_lim"] for f in fs])
        order = np.argsort(zl)
        lz, lf = np.log(zl[order]), np.log(np.array(fs)[order])
        x = np.log(self.paper_zlim[policy])
        return float(np.exp(np.interp(x, lz, lf))) if lz[0] <= x <= lz[-1] else float("nan")

    def edge(self, variant):
        """Smallest factor at which the 9:2 NRHO is consistent under ``variant`` (None if none)."""
        return next((f for f in self.factors(variant) if self.consistent_on("9:2 NRHO", f, variant)), None)

    def report(self, f_tune: float) -> str:
        """The map's cells and its two readings as text."""
        lines = [f"{'orbit':25s} {'policy':7s} {'setting':24s} {'f':>5s} {'z_lim':>11s} {'FP+MD':>6s} "
                 f"{'inconsistent runs H0 fwd/smo, H1 fwd/smo':>42s}"]
        for (o, p, f, v), c in self.cells.items():
            lines.append(f"{o:25s} {p:7s} {v:24s} {f:5.2f} {c['z_lim'] * 1e3:8.2f} mm/s {c['err']:6.3f} "
                         f"{100 * c['h0'][0]:9.0f} % / {100 * c['h0'][1]:3.0f} %, "
                         f"{100 * c['h1'][0]:3.0f} % / {100 * c['h1'][1]:3.0f} %")
        lines.append(f"consistency reading: f_c = {self.f_c:g} (every orbit, policy and hypothesis at most 10 % "
                     f"inconsistent runs; factors meeting it: {self.consistent_factors})")
        lines.append("threshold reading: the 9:2 z_lim of the map equals the paper's at f = "
                     + ", ".join(f"{self.f_match(p):.2f} ({p})" for p in self.policies)
                     + f"; the training runs below use f = {f_tune}")
        both = [(v, f) for v in self.variants for f in self.factors(v)
                if all(self.worst("9:2 NRHO", p, f, v) <= CONSISTENT_FRACTION
                       and abs(self.cells["9:2 NRHO", p, f, v]["z_lim"] / self.paper_zlim[p] - 1) <= 0.25
                       for p in self.policies)]
        lines.append("9:2 NRHO settings that are consistent (both policies) with both thresholds within 25 % of the "
                     "paper's: " + (", ".join(f"{v} at f = {f:g}" for v, f in both) or "none"))
        lines.append("9:2 NRHO settings consistent at f = 0.1: "
                     + (", ".join(v for v in self.variants if self.consistent_on("9:2 NRHO", 0.1, v)) or "none"))
        for v in self.variants[1:]:
            ok = [f for f in self.f_side if self.consistent_on("9:2 NRHO", f, v)]
            lines.append(
                f"9:2 NRHO, {v:14s}: consistent (both policies) at f = {ok or 'none of ' + str(self.f_side)}; z_lim / "
                "paper at f = " + ", ".join(
                    f"{f:g}: " + " / ".join(f"{self.cells['9:2 NRHO', p, f, v]['z_lim'] / self.paper_zlim[p]:.2f}"
                                            for p in self.policies) for f in self.f_side) + " (active / quiet)")
        return "\n".join(lines)


def _policy_studies(jobs, batch_size: int, executor) -> list:
    """:func:`detection.run_policy_studies` (pooled); ``batch_size=0`` (single-trial OCBE) runs one study at a time."""
    if batch_size == 0:
        return [det.run_policy_study(*job, batch_size=0, executor=executor, progress=False) for job in jobs]
    return det.run_policy_studies(jobs, batch_size=batch_size, executor=executor)


def _bootstrap_task(task) -> np.ndarray:
    z0, z1, n_boot, seed = task
    return det.threshold_bootstrap(z0, z1, n_boot, np.random.default_rng(seed))


def _bootstraps(tasks, executor) -> list:
    """:func:`detection.threshold_bootstrap` of every ``(z_h0, z_h1, n_boot, seed)`` in ``tasks``, side by side on
    ``executor`` (each draws from its own ``numpy.random.default_rng(seed)``, so the results are those of the serial
    loop, bit for bit, whatever runs them).  A bootstrap of 40 resamples at the paper's 500 + 3000 runs takes 1-2 s
    (two kernel density estimates on a 1001-point grid per resample); the main process used to run them one after
    the other while the Monte Carlo workers waited."""
    return montecarlo.map_tasks(_bootstrap_task, tasks, executor=executor, progress=False)


def run_tuning_map(system, orbits: dict, policies: dict, variants: dict, f_grid, f_side, n_map, seed, *,
                   paper_zlim: dict, q_base_km2_s3: float, window_hours: float, sigma_angle_rad: float,
                   half_size_orbits=(), batch_size: int = 8, executor=None) -> TuningMap:
    """Run the tuning map: every orbit and policy over ``f_grid`` at the first (base) setting of ``variants``, and the
    9:2 NRHO over ``f_side`` at the others.

    Parameters
    ----------
    system : CR3BP
    orbits : dict
        Name -> PeriodicOrbit (must contain "9:2 NRHO").
    policies : dict
        Name -> detection.StationKeepingPolicy.
    variants : dict
        Setting name -> overrides among ``sigma_angle_rad``, ``window_hours``, ``q_base`` (the first: none).
    f_grid, f_side : sequence of float
        Window weight factors (units of :func:`detection.window_control_weight`).
    n_map : (int, int)
        H0 and H1 runs per cell (at least 4 each; half on ``half_size_orbits``).
    seed : int or sequence
        Cell ``i`` (in the order above) uses the seed ``[*seed, i]``.
    paper_zlim : dict
        Policy -> paper's threshold, m/s (for the threshold reading).
    q_base_km2_s3, window_hours, sigma_angle_rad : float
        The base setting.
    """
    check_system(system)
    validation.dict_of(orbits, "orbits", PeriodicOrbit, "cislunar.cr3bp.orbits.PeriodicOrbit")
    if "9:2 NRHO" not in orbits:
        raise ValueError(f"orbits must contain the '9:2 NRHO' (the side axes run on it); got {list(orbits)}")
    validation.dict_of(policies, "policies", det.StationKeepingPolicy, "detection.StationKeepingPolicy")
    validation.dict_of(variants, "variants", dict, "dict of overrides")
    for v, ov in variants.items():
        unknown = set(ov) - {"sigma_angle_rad", "window_hours", "q_base"}
        if unknown:
            raise ValueError(f"variants[{v!r}] may override only sigma_angle_rad, window_hours and q_base; got "
                             f"{sorted(unknown)}")
    f_grid = tuple(float(f) for f in _positive_values(f_grid, "f_grid"))
    f_side = tuple(float(f) for f in _positive_values(f_side, "f_side"))
    validation.instance(n_map, "n_map", (tuple, list, np.ndarray), "a pair (H0 runs, H1 runs)")
    if len(n_map) != 2:
        raise ValueError(f"n_map must be a pair (H0 runs, H1 runs); got {n_map!r}")
    n_map = tuple(validation.integer(n, "n_map", minimum=1) for n in n_map)
    seed = validation.int_seed_list(seed, "seed", why="each cell appends its index")
    validation.instance(paper_zlim, "paper_zlim", dict, "a dict policy -> threshold (m/s)")
    for p in policies:
        if p not in paper_zlim:
            raise ValueError(f"paper_zlim must give a threshold for every policy; missing {p!r}")
        validation.positive(paper_zlim[p], f"paper_zlim[{p!r}]")
    q_base_km2_s3 = validation.positive(q_base_km2_s3, "q_base_km2_s3")
    window_hours = validation.positive(window_hours, "window_hours")
    sigma_angle_rad = validation.positive(sigma_angle_rad, "sigma_angle_rad")
    if isinstance(half_size_orbits, (str, bytes)):
        raise validation.ArgumentTypeError(f"half_size_orbits must be a sequence of orbit names; got a single "
                                           f"{type(half_size_orbits).__name__} {half_size_orbits!r}")
    try:
        half = tuple(half_size_orbits)
    except TypeError:
        raise validation.ArgumentTypeError(f"half_size_orbits must be a sequence of orbit names; got "
                                           f"{type(half_size_orbits).__name__}") from None
    if any(o not in orbits for o in half):
        raise ValueError(f"half_size_orbits must name orbits of orbits ({list(orbits)}); got {half!r}")
    batch_size = validation.integer(batch_size, "batch_size", minimum=0)
    _check_executor(executor)
    names = tuple(variants)
    base = names[0]
    cells = [(o, p, f, base) for o in orbits for p in policies for f in f_grid]
    cells += [("9:2 NRHO", p, f, v) for v in names[1:] for p in policies for f in f_side]
    jobs = []
    make_setup = _setup_maker(system)
    for i, (o, p, f, v) in enumerate(cells):
        ov = variants[v]
        wh = ov.get("window_hours", window_hours)
        setup = make_setup(orbits[o], f * det.window_control_weight(policies[p], wh), ov.get("q_base", q_base_km2_s3),
                           window_hours=wh, sigma_angle_rad=ov.get("sigma_angle_rad", sigma_angle_rad))
        k = 0.5 if o in half_size_orbits else 1.0  # the outer band's period is 10 days: half the runs
        jobs.append((setup, policies[p], max(int(k * n_map[0]), 4), max(int(k * n_map[1]), 4), 0, [*seed, i]))
    # every cell's Monte Carlo in one pooled sweep (the same trials as one run_policy_study per cell)
    studies = _policy_studies(jobs, batch_size, executor)
    out = {}
    for (o, p, f, v), st in zip(cells, studies):
        out[o, p, f, v] = {"z_lim": st.threshold.z_lim, "err": st.threshold.total_error,
                           "h0": st.h0.inconsistent_runs, "h1": st.h1.inconsistent_runs, "n": (len(st.h0), len(st.h1)),
                           "slope": np.polyfit(st.h1.magnitude, st.h1.z, 1)[0]}
    return TuningMap(out, tuple(orbits), tuple(policies), names, tuple(f_grid), tuple(f_side), dict(paper_zlim))


# ---------------------------------------------------------------------------------------------------------------
# Figs. 10-13: one run under the two tunings
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TuningDemo:
    """One quiet-policy run filtered twice: with the window weight held constant over the period (Figs. 10-11) and
    with it only in the apoapsis window (Figs. 12-13).

    Attributes
    ----------
    setup : detection.DetectionSetup
        The window-tuned setup the run was drawn on.
    inputs : detection.TrialInputs
        The run (truth, measurements, hand-off).
    control_weights : dict
        Tuning (``"constant"``, ``"apoapsis window"``) -> control weight, a scalar or per interval (nondimensional).
    runs : dict
        Tuning -> the OCBE result (:func:`detection.run_trial_filter`).
    panels : dict
        Tuning -> :class:`panels.PanelSeries` (the series the figures draw).
    burn_days : float
        Burn epoch, days from the start of the track.
    """

    setup: det.DetectionSetup
    inputs: det.TrialInputs
    control_weights: dict
    runs: dict
    panels: dict
    burn_days: float

    @property
    def nees_quantile(self) -> float:
        """99.9 % quantile of the 6-dof chi-square law (an epoch above it is inconsistent)."""
        return float(stats.chi2.ppf(NEES_PROBABILITY, 6))

    def summary(self, tuning: str) -> dict:
        """Per tuning: ``over`` (fraction of epochs above the NEES quantile, forward and smoothed), ``z_f`` and
        ``z_s`` (forward and smoothed control integral, mm/s), ``metric_over`` (forward epochs with the normalised
        metric above 1), ``trigger`` (first epoch of three consecutive exceedances, None if the adaptive rule would
        not fire), ``sig_final`` (final forward 3-sigma position km and velocity mm/s) and ``contrast`` (control
        spike contrast at the burn, forward and smoothed)."""
        validation.choice(tuning, "tuning", tuple(self.runs))
        r, pn = self.runs[tuning], self.panels[tuning]
        v_mm = self.setup.system.velocity_unit_km_s * 1e6
        return dict(over=np.mean(pn.nees > self.nees_quantile, axis=1), z_f=r.z_step * v_mm, z_s=r.z_smooth * v_mm,
                    metric_over=int(np.sum(pn.normalized_metric[0] > 1)),
                    trigger=ad.first_detection(pn.metric[0], pn.limit),
                    sig_final=(pn.position_3sigma_km[0, -1], pn.velocity_3sigma_m_s[0, -1] * 1e3),
                    contrast=pn.spike_contrast(self.burn_days))

    def report(self) -> str:
        """One line per tuning: z, NEES exceedances, the forward metric, the final bounds and the spike contrast."""
        lines = []
        for name in self.runs:
            f = self.summary(name)
            n_epochs = self.panels[name].normalized_metric[0].size
            lines.append(
                f"{name:16s}: z forward {f['z_f']:6.2f} mm/s, smoothed {f['z_s']:6.2f} mm/s | epochs above "
                f"NEES 99.9 %: forward {100 * f['over'][0]:.0f} %, smoothed {100 * f['over'][1]:.0f} % | forward metric "
                f"above its limit at {f['metric_over']} of {n_epochs} epochs (adaptive rule "
                f"{'would' if f['trigger'] is not None else 'would not'} fire) | final forward 3-sigma "
                f"{f['sig_final'][0]:.2f} km, {f['sig_final'][1]:.1f} mm/s | control spike contrast at the burn: "
                f"forward {f['contrast'][0]:.3g}, smoothed {f['contrast'][1]:.3g}")
        return "\n".join(lines)

    def window_after_burn(self) -> dict:
        """The window tuning's forward errors after the burn (Fig. 12): ``k_burn`` (first epoch after it),
        ``hours_after``, ``velocity_ratio`` and ``position_ratio`` (error over its 3-sigma bound), ``k_end`` (end of
        the stretch with the velocity ratio above 0.8 right after the burn) and ``nees_over`` (forward NEES above its
        quantile, per epoch after the burn)."""
        pw, b = self.panels["apoapsis window"], self.burn_days
        k_b = int(np.searchsorted(pw.t_days, b, side="right"))
        v_ratio = pw.velocity_error_m_s[0, k_b:] / pw.velocity_3sigma_m_s[0, k_b:]
        near = v_ratio > 0.8  # velocity error within 20 % of its 3-sigma bound (or above it)
        return dict(k_burn=k_b, hours_after=(pw.t_days[k_b:] - b) * 24, velocity_ratio=v_ratio,
                    position_ratio=pw.position_error_km[0, k_b:] / pw.position_3sigma_km[0, k_b:],
                    k_end=int(np.argmin(near)) if not near.all() else near.size - 1,
                    nees_over=pw.nees[0, k_b:] > self.nees_quantile)

    def fig12_report(self) -> str:
        """The Fig. 12 readout: how long the forward errors stay near their bounds after the burn, the NEES
        exceedances and the forward 3-sigma position bound after the window."""
        pw, a = self.panels["apoapsis window"], self.window_after_burn()
        k_b, h, v_ratio, k_end, over = a["k_burn"], a["hours_after"], a["velocity_ratio"], a["k_end"], a["nees_over"]
        below_half = np.flatnonzero(v_ratio < 0.5)
        lines = [f"forward velocity error / its 3-sigma bound after the burn: {v_ratio[0]:.2f} at +{h[0]:.0f} h, above "
                 f"0.8 at the first {k_end} epoch(s), below 0.5 from "
                 + (f"+{h[below_half[0]]:.0f} h" if below_half.size else "never")]
        for what, r_ in (("velocity", v_ratio), ("position", a["position_ratio"])):
            later = np.flatnonzero(r_ > 0.8)
            later = later[later >= k_end]
            lines.append(f"forward {what} error above 0.8 of its 3-sigma bound at {later.size} epochs from "
                         f"+{h[k_end]:.0f} h"
                         + (f", between day {pw.t_days[k_b + later[0]]:.2f} and {pw.t_days[k_b + later[-1]]:.2f}; "
                            f"largest ratio {r_[later].max():.2f}" if later.size else ""))
        lines.append(f"forward NEES above its 99.9 % quantile at {int(over.sum())} epochs after the burn, the first "
                     f"{int(np.argmin(over)) if not over.all() else over.size} of them in a row")
        k_top = k_b + int(np.argmax(pw.position_3sigma_km[0, k_b:]))
        lines.append(f"forward 3-sigma position: {pw.position_3sigma_km[0, k_b]:.2f} km just after the burn, rising to "
                     f"{pw.position_3sigma_km[0, k_top]:.2f} km at day {pw.t_days[k_top]:.2f} (burn at day "
                     f"{self.burn_days:.2f}), {pw.position_3sigma_km[0, -1]:.2f} km at the end")
        return "\n".join(lines)

    def fig13_report(self) -> str:
        """The Fig. 13 readout: smoothed over forward z for both tunings, and the window tuning's smoothed z over
        the burn."""
        fs_c, fs_w = self.summary("constant"), self.summary("apoapsis window")
        burn_mm_s = self.inputs.magnitude_m_s * 1e3
        return (f"smoothed over forward z: constant {fs_c['z_s'] / fs_c['z_f']:.1f}, window "
                f"{fs_w['z_s'] / fs_w['z_f']:.1f}; the window tuning's smoothed z is {fs_w['z_s'] / burn_mm_s:.2f} of "
                f"the {burn_mm_s:.0f} mm/s burn")


def run_tuning_demo(setup: det.DetectionSetup, seed, *, magnitude_m_s: float = 0.05,
                    direction=(np.pi / 2, 0.0)) -> TuningDemo:
    r"""Draw one run with a burn of ``magnitude_m_s`` along ``direction`` (azimuth, elevation in rad; default
    :math:`+\hat\jmath`) on the window-tuned ``setup`` (generator seeded with ``seed``) and filter it with the
    window weight held constant over the period and with the setup's apoapsis window (Figs. 10-13)."""
    _check_setup(setup)
    validation.seed_entropy(seed, "seed")
    validation.positive(magnitude_m_s, "magnitude_m_s")
    inputs = det.draw_trial(np.random.default_rng(seed), setup, magnitude_m_s=magnitude_m_s, direction=direction)
    weights = {"constant": setup.control_weight.max(), "apoapsis window": setup.control_weight}
    runs = {name: det.run_trial_filter(setup, inputs, control_weight=q) for name, q in weights.items()}
    sc = setup.scenario
    panels = {name: ocbe_panels.panel_series(setup.system, r, inputs.truth, weights[name], inputs.y,
                                             setup.observer_states, sc.model, sc.meas_cov) for name, r in runs.items()}
    return TuningDemo(setup, inputs, weights, runs, panels, float(setup.t_maneuver * setup.system.time_unit_days))


# ---------------------------------------------------------------------------------------------------------------
# Figs. 10-11 on many runs: constant against window tuning
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SpikeStudy:
    """The same quiet-policy runs with and without a burn, filtered with the constant and the window tuning.

    Attributes
    ----------
    cells : dict
        ``(tuning, hypothesis)`` -> dict with ``inc`` (fractions of inconsistent runs, forward and smoothed),
        ``contrast`` (per run, forward and smoothed control spike contrast at the burn, shape (n, 2)), ``sig_km``
        (mean forward 3-sigma position bound, km) and ``after_burn`` (share of the forward NEES exceedances in the day
        after the burn).
    n : int
        Runs per hypothesis.
    """

    cells: dict
    n: int

    @property
    def fig10_limit(self) -> float:
        """Largest fraction of inconsistent runs per cell for Fig. 10: :data:`CONSISTENT_FRACTION`, the chapter's rule
        for "consistent" (the Figs. 12-13 rows).  (Until 2026-11-26, session h, 10 % plus two binomial standard errors,
        14.2 % for 200 runs, a widening declared after 10.5 % had been seen.)"""
        return CONSISTENT_FRACTION

    @property
    def fig10_ok(self) -> bool:
        """Constant tuning: every cell at most :attr:`fig10_limit` inconsistent, and a larger bound than the window
        tuning's."""
        c = self.cells
        return bool(max(*c["constant", "H0"]["inc"], *c["constant", "H1"]["inc"]) <= self.fig10_limit
                    and c["constant", "H1"]["sig_km"] > c["apoapsis window", "H1"]["sig_km"])

    @property
    def fig11_h1(self) -> float:
        """Burn runs (constant tuning) whose smoothed contrast is at least 2 and above the forward one."""
        c = self.cells["constant", "H1"]["contrast"]
        return float(np.mean((c[:, 1] >= 2) & (c[:, 1] > c[:, 0])))

    @property
    def fig11_h0(self) -> float:
        """Runs without a burn (constant tuning) whose smoothed contrast stays below 2."""
        return float(np.mean(self.cells["constant", "H0"]["contrast"][:, 1] < 2))

    def report(self) -> str:
        lines = [f"{self.n} quiet-policy runs without a burn (H0) and {self.n} with one (H1), each filtered with both "
                 "tunings"]
        for (tuning, h), v in self.cells.items():
            c = v["contrast"]
            lines.append(
                f"{tuning:16s} {h}: inconsistent runs fwd {100 * v['inc'][0]:4.1f} %, smo {100 * v['inc'][1]:4.1f} % | "
                f"mean forward 3-sigma position {v['sig_km']:6.2f} km | spike contrast median fwd "
                f"{np.median(c[:, 0]):7.3g}, smo {np.median(c[:, 1]):7.3g} | runs with smoothed contrast >= 2 and above "
                f"forward: {100 * np.mean((c[:, 1] >= 2) & (c[:, 1] > c[:, 0])):.0f} % | forward NEES exceedances in "
                f"the day after the burn: {100 * v['after_burn']:.0f} %")
        return "\n".join(lines)


def run_spike_study(constant: det.DetectionSetup, window: det.DetectionSetup, n: int, seed, *,
                    executor=None) -> SpikeStudy:
    """Draw ``n`` runs without a burn and ``n`` with a quiet-policy burn (seeds ``[*seed, 0]`` and ``[*seed, 1]``,
    spawned per run) on the ``window`` setup, and filter both sets with both tunings (batched OCBE, lockstep groups
    through ``executor`` when given)."""
    _check_setup(constant, "constant")
    _check_setup(window, "window")
    if constant.scenario.t.shape != window.scenario.t.shape or not np.allclose(constant.scenario.t,
                                                                             window.scenario.t):
        raise ValueError("constant and window must share the measurement epochs (the same runs are filtered on both)")
    n = validation.integer(n, "n", minimum=1)
    seed = validation.int_seed_list(seed, "seed", why="the two hypotheses append an index")
    _check_executor(executor)
    sc = window.scenario
    inputs = {h: det.draw_trials(np.random.default_rng([*seed, j]).spawn(n), window, pol)
              for j, (h, pol) in enumerate((("H0", None), ("H1", det.QUIET_POLICY)))}
    lim = nees_limit()
    k_b = int(np.searchsorted(sc.t, window.t_maneuver, side="right"))
    cases = [(tuning, s, h) for tuning, s in (("constant", constant), ("apoapsis window", window)) for h in inputs]
    filtered = det.filter_trial_sets([(s, inputs[h]) for _, s, h in cases], executor=executor)
    cells = {}
    for (tuning, s, h), r in zip(cases, filtered):
        runs = inputs[h]
        nf = np.array([nees(r.x_filt[b], r.P_filt[b], c.truth) for b, c in enumerate(runs)])
        ns = np.array([nees(r.x_smooth[b], r.P_smooth[b], c.truth) for b, c in enumerate(runs)])
        exc = nf > lim
        cells[tuning, h] = {
            "inc": tuple(float(np.mean(np.mean(x > lim, axis=1) > tracking.DIVERGED_FRACTION)) for x in (nf, ns)),
            "contrast": det.control_spike_contrast(s, r),
            "sig_km": float(np.mean(3 * np.sqrt(np.trace(r.P_filt[:, :, :3, :3], axis1=2, axis2=3))))
            * s.system.length_unit_km,
            # share of the forward exceedances that fall in the day after the burn (the first 12 epochs after it)
            "after_burn": float(exc[:, k_b:k_b + 12].sum() / max(exc.sum(), 1))}
    return SpikeStudy(cells, n)


# ---------------------------------------------------------------------------------------------------------------
# The training and test Monte Carlo at both tunings (Figs. 14-21, Tables 5-8)
# ---------------------------------------------------------------------------------------------------------------

#: The two readings of the window weight, as the tables label them.
TAGS = ("f = 0.1", "f_c")


def ratio_text(v) -> str:
    """A Fig. 16 ratio as printed (NaN: no burn in a sector)."""
    v = validation.real(v, "v", finite=False)
    return "no burn in a sector (small sample)" if np.isnan(v) else f"{v:.2f}"


@dataclass(frozen=True)
class TrainingStudies:
    """The paper's Monte Carlo per orbit and policy at the two tunings, with bootstrap standard errors.

    Attributes
    ----------
    studies : dict
        Tag (:data:`TAGS`) -> {(orbit, policy) -> detection.PolicyStudy}.
    boot : dict
        ((orbit, policy), tag) -> bootstrap array of (z_lim, FP + MD) (detection.threshold_bootstrap).
    nees_rows : dict
        (orbit, policy, hypothesis) -> ``tune``/``c`` (inconsistent fractions, forward and smoothed, at f = 0.1 and
        f_c) and ``mean`` (mean NEES, forward and smoothed, at f = 0.1).
    lin : dict
        (orbit, policy, tag) -> (slope of z on the magnitude, their correlation, Fig. 16 azimuth ratio, skewness of
        H1 z).
    """

    studies: dict
    boot: dict
    nees_rows: dict
    lin: dict

    @property
    def tuned(self) -> dict:
        return self.studies[TAGS[0]]

    @property
    def predicted(self) -> dict:
        return self.studies[TAGS[1]]

    def se(self, key, tag: str, col: int) -> float:
        """Bootstrap standard error of z_lim (``col`` 0, m/s) or FP + MD (``col`` 1)."""
        return float(self.boot[key, tag][:, col].std(ddof=1))

    def accuracy(self, key, tag: str) -> float:
        return self.studies[tag][key].score.accuracy

    @property
    def worst_predicted(self) -> float:
        """Worst fraction of inconsistent runs over every cell at f_c."""
        return max(max(v["c"]) for v in self.nees_rows.values())

    def tables_report(self, f_c: float) -> str:
        lines = []
        for tag in TAGS:
            which = "f = 0.1" if tag == TAGS[0] else f"f_c = {f_c:g}"
            lines.append(f"Tables 5-6 at {which} (expected rates from the PDFs; bootstrap standard errors)")
            lines.append(f"{'orbit':25s} {'policy':7s} {'z_lim':>18s} {'false pos.':>11s} {'missed det.':>12s} "
                         f"{'FP + MD':>15s} {'crossings':>9s} {'H0 mean':>10s} {'H1 mean':>10s}")
            for (o, p), st in self.studies[tag].items():
                th = st.threshold
                lines.append(
                    f"{o:25s} {p:7s} {th.z_lim * 1e3:8.2f} +- {self.se((o, p), tag, 0) * 1e3:5.2f} mm/s "
                    f"{th.false_positive:11.4f} {th.missed_detection:12.4f} {th.total_error:7.4f} +- "
                    f"{self.se((o, p), tag, 1):.4f} {th.crossings.size:9d} {st.h0.z.mean() * 1e3:7.2f} mm/s "
                    f"{st.h1.z.mean() * 1e3:7.2f} mm/s")
        return "\n".join(lines)

    def nees_report(self, orbit_names) -> str:
        st = self.tuned
        lines = ["training runs per policy (H0 + H1, each tuning): "
                 + "; ".join(f"{o} {len(st[o, 'active'].h0)} + {len(st[o, 'active'].h1)}" for o in orbit_names),
                 f"{'orbit':25s} {'policy':7s} {'hyp':4s} {'f = 0.1: inconsistent fwd / smo, mean NEES fwd / smo':>52s} "
                 f"{'f_c: inconsistent fwd / smo':>30s}"]
        for (o, p, hyp), r in self.nees_rows.items():
            lines.append(f"{o:25s} {p:7s} {hyp:4s} {100 * r['tune'][0]:14.1f} % / {100 * r['tune'][1]:4.1f} %, "
                         f"{r['mean'][0]:6.2f} / {r['mean'][1]:5.2f} {100 * r['c'][0]:19.1f} % / "
                         f"{100 * r['c'][1]:4.1f} %")
        bad = {k: v["tune"] for k, v in self.nees_rows.items() if max(v["tune"]) > CONSISTENT_FRACTION}
        lines.append("cells with more than 10 % inconsistent runs at f = 0.1 (forward / smoothed): "
                     + ("; ".join(f"{o} {p} {h}: {100 * v[0]:.1f} % / {100 * v[1]:.1f} %"
                                  for (o, p, h), v in bad.items()) or "none"))
        lines.append(f"every such cell has a burn (H1): {all(h == 'H1' for _, _, h in bad)}; worst cell at f_c: "
                     f"{100 * self.worst_predicted:.1f} % of runs")
        return "\n".join(lines)

    def lin_report(self) -> str:
        return "\n".join(
            f"{tag:7s} {o:25s} {p:7s}: z vs magnitude slope {v[0]:.2f}, corr {v[1]:.3f}; z/|dv| at azimuth +-90 over "
            f"0/180 (|el| < 45 deg) = {ratio_text(v[2])}; skewness of H1 z = {v[3]:.2f}"
            for (o, p, tag), v in self.lin.items())

    def accuracy_report(self, f_c: float) -> str:
        lines = []
        for tag in TAGS:
            label = "f = 0.1" if tag == TAGS[0] else f"f_c = {f_c:g}"
            lines.append(f"{label}: {'orbit':25s} {'policy':7s} {'H0 -> H0':>9s} {'H0 -> H1':>9s} {'H1 -> H1':>9s} "
                         f"{'H1 -> H0':>9s} {'accuracy':>9s}")
            for (o, p), st in self.studies[tag].items():
                s = st.score
                lines.append(f"{'':{len(label) + 2}s}{o:25s} {p:7s} {s.true_negative:9d} {s.false_positive:9d} "
                             f"{s.true_positive:9d} {s.missed_detection:9d} {100 * s.accuracy:8.1f}%")
        return "\n".join(lines)

    def candidates_report(self, orbit_names, policy_names) -> str:
        lines = []
        for o in orbit_names:
            for tag in TAGS:
                g = self.studies[tag]
                errs = " / ".join(f"{g[o, p].threshold.total_error:.4f} +- {self.se((o, p), tag, 1):.4f}"
                                  for p in policy_names)
                worst = max(max(self.nees_rows[o, p, h]["tune" if tag == TAGS[0] else "c"]) for p in policy_names
                            for h in ("H0", "H1"))
                lines.append(f"{o:25s} {tag:8s}: accuracy active {100 * self.accuracy((o, 'active'), tag):.1f} %, "
                             f"quiet {100 * self.accuracy((o, 'quiet'), tag):.1f} % ({g[o, 'active'].score.n} tests "
                             f"each); expected FP + MD active / quiet {errs}; worst consistency cell {100 * worst:.0f} % "
                             "of runs")
        return "\n".join(lines)

    def stable_difference_report(self, stable_names, policy_names) -> str:
        res = {(o, tag): [abs(self.studies[tag][o, p].threshold.total_error
                              - self.studies[tag]["9:2 NRHO", p].threshold.total_error)
                          / np.hypot(self.se((o, p), tag, 1), self.se(("9:2 NRHO", p), tag, 1)) for p in policy_names]
               for o in stable_names for tag in TAGS}
        return ("difference of the expected error from the 9:2 NRHO's, in combined standard errors (active, quiet): "
                + "; ".join(f"{o} {tag}: {v[0]:.1f}, {v[1]:.1f}" for (o, tag), v in res.items()))


def run_training_studies(setups: dict, setups_c: dict, policies: dict, sizes: dict, seed: int, n_boot: int, *,
                         batch_size: int = 8, executor=None) -> TrainingStudies:
    """The training and test Monte Carlo of every orbit and policy at f = 0.1 (``setups``, seeds ``[seed, i, j]``)
    and at f_c (``setups_c``, seeds ``[seed, 200 + i, j]``), then ``n_boot`` bootstrap resamples of each threshold
    (seeds ``[seed, 90, n, w]``).  ``sizes``: orbit -> (H0 train, H1 train, tests per hypothesis)."""
    validation.dict_of(setups, "setups", det.DetectionSetup, "detection.DetectionSetup")
    validation.dict_of(setups_c, "setups_c", det.DetectionSetup, "detection.DetectionSetup")
    validation.dict_of(policies, "policies", det.StationKeepingPolicy, "detection.StationKeepingPolicy")
    validation.instance(sizes, "sizes", dict, "a dict orbit -> (H0 train, H1 train, tests per hypothesis)")
    orbit_names = list(dict.fromkeys(o for o, _ in setups))
    for o in orbit_names:
        for p in policies:
            if (o, p) not in setups:
                raise ValueError(f"setups must hold a setup per (orbit, policy); missing {(o, p)!r}")
            if (o, p) not in setups_c:
                raise ValueError(f"setups_c must hold a setup per (orbit, policy) of setups; missing {(o, p)!r}")
        n3 = sizes.get(o)
        if not isinstance(n3, (tuple, list)) or len(n3) != 3:
            raise ValueError(f"sizes must give (H0 train, H1 train, tests per hypothesis) for {o!r}; got {n3!r}")
        validation.integer(n3[0], f"sizes[{o!r}][0]", minimum=2)
        validation.integer(n3[1], f"sizes[{o!r}][1]", minimum=2)
        validation.integer(n3[2], f"sizes[{o!r}][2]", minimum=0)
    seed = validation.integer(seed, "seed", minimum=0)
    n_boot = validation.integer(n_boot, "n_boot", minimum=1)
    batch_size = validation.integer(batch_size, "batch_size", minimum=0)
    _check_executor(executor)
    keys = [(o, p) for o in orbit_names for p in policies]
    jobs = [(setups[o, p], policies[p], *sizes[o], [seed, i, j]) for i, o in enumerate(orbit_names)
            for j, p in enumerate(policies)]
    jobs += [(setups_c[o, p], policies[p], *sizes[o], [seed, 200 + i, j]) for i, o in enumerate(orbit_names)
             for j, p in enumerate(policies)]
    # all training and test Monte Carlo in one pooled sweep (the same trials as one run_policy_study per case)
    done = _policy_studies(jobs, batch_size, executor)
    studies, studies_c = dict(zip(keys, done[:len(keys)])), dict(zip(keys, done[len(keys):]))
    where = [((key, which), (st.h0.z, st.h1.z, n_boot, [seed, 90, n, w]))
             for w, (which, group) in enumerate(((TAGS[0], studies), (TAGS[1], studies_c)))
             for n, (key, st) in enumerate(group.items())]
    boot = dict(zip([k for k, _ in where], _bootstraps([t for _, t in where], executor)))
    nees_rows = {}
    for (o, p) in studies:
        for hyp in ("H0", "H1"):
            a, b = getattr(studies[o, p], hyp.lower()), getattr(studies_c[o, p], hyp.lower())
            nees_rows[o, p, hyp] = {"tune": a.inconsistent_runs, "c": b.inconsistent_runs,
                                    "mean": (float(a.nees_mean_fwd.mean()), float(a.nees_mean_smooth.mean()))}
    lin = {}
    for group, tag in ((studies, TAGS[0]), (studies_c, TAGS[1])):
        for (o, p), st in group.items():
            h1 = st.h1
            lin[o, p, tag] = (np.polyfit(h1.magnitude, h1.z, 1)[0], np.corrcoef(h1.magnitude, h1.z)[0, 1],
                              det.azimuth_contrast(h1), stats.skew(h1.z))
    return TrainingStudies({TAGS[0]: studies, TAGS[1]: studies_c}, boot, nees_rows, lin)


# ---------------------------------------------------------------------------------------------------------------
# The +-j search (Figs. 16, 20)
# ---------------------------------------------------------------------------------------------------------------

#: Burn directions of the +-j search: (azimuth, elevation) in degrees, rotating frame.
DIRECTIONS = {"+i": (0.0, 0.0), "-i": (180.0, 0.0), "+j": (90.0, 0.0), "-j": (-90.0, 0.0), "+k": (0.0, 90.0),
              "-k": (0.0, -90.0)}


@dataclass(frozen=True)
class PmJSearch:
    """Mean z of 1 m/s burns along +-i, +-j, +-k per window factor, angle noise and burn time, and the +-j contrast.

    Attributes
    ----------
    cells : dict
        (f, noise [micro-rad], burn offset [h]) -> (z per direction of :data:`DIRECTIONS` [m/s], contrast: mean z of
        +-j over the mean of the four others).
    offsets_h : tuple of float
    line_of_sight : ndarray, shape (3,)
        Unit vector from the L2 observer to the apoapsis (rotating frame).
    range_km : float
    """

    cells: dict
    f_values: tuple
    offsets_h: tuple
    line_of_sight: np.ndarray
    range_km: float

    @property
    def best(self) -> tuple:
        """(f, noise, offset) of the largest contrast with the burn at apoapsis, and that contrast."""
        k, v = max(((k, v) for k, v in self.cells.items() if k[2] == 0.0), key=lambda kv: kv[1][1])
        return k, v[1]

    def contrasts_at(self, noise: float) -> list:
        return [c for (f, s, o), (z, c) in self.cells.items() if s == noise]

    def burn_time_effect(self) -> float:
        """Largest change of the contrast with the burn time at the best (f, noise)."""
        (f, s, _), _ = self.best
        return max(abs(self.cells[f, s, o][1] - self.cells[f, s, 0.0][1]) for o in self.offsets_h)

    def report(self) -> str:
        (f_pm, sig_pm, _), c_best = self.best
        lines = [f"line of sight L2 observer -> apoapsis (rotating frame): {np.round(self.line_of_sight, 3)}, range "
                 f"{self.range_km:.0f} km", "z of 1 m/s burns [m/s] (" + ", ".join(DIRECTIONS) + ") and the +-j contrast"]
        lines += [f"f = {f:4.2f}, noise {s:6.0f} urad, burn {o:+.0f} h: " + " ".join(f"{z:.3f}" for z in zs)
                  + f" | contrast {c:.2f}" for (f, s, o), (zs, c) in self.cells.items()]
        c10 = self.contrasts_at(10.0)
        lines.append(f"largest contrast with the burn at apoapsis {c_best:.2f} at f = {f_pm:g}, {sig_pm:g} urad (over "
                     f"all burn times {max(c for z, c in self.cells.values()):.2f}); at our noise (10 urad) the contrast "
                     f"stays within {min(c10):.2f}-{max(c10):.2f}")
        for sig in (10.0, sig_pm):  # our noise, and the noise where the pattern is strongest
            lines.append(
                f"at {sig:g} urad, per f: change of the contrast with the burn time (max - min over "
                f"{', '.join(f'{o:+g}' for o in self.offsets_h)} h) and range of z of the 1 m/s burns [m/s]: "
                + "; ".join(f"f = {f:g}: {np.ptp([self.cells[f, sig, o][1] for o in self.offsets_h]):.2f}, z "
                            f"{min(self.cells[f, sig, o][0].min() for o in self.offsets_h):.2f}-"
                            f"{max(self.cells[f, sig, o][0].max() for o in self.offsets_h):.2f}" for f in self.f_values))
        return "\n".join(lines)


def run_pm_j_search(system, orbit, f_values, noise_urad, offsets_h, n_repeats: int, seed, *, q_base_km2_s3: float,
                    window_hours: float, executor=None) -> PmJSearch:
    """1 m/s burns along the six axes (the same noise draws for every direction, seed ``seed``) for every window
    factor (active policy's variance-matched weight), angle noise and burn time (:func:`detection.direction_response`);
    the filter groups go through ``executor`` when given (results do not depend on it)."""
    check_system(system)
    _check_orbit(orbit)
    f_values = tuple(float(f) for f in _positive_values(f_values, "f_values"))
    noise_urad = tuple(float(s) for s in _positive_values(noise_urad, "noise_urad"))
    offsets_h = tuple(float(o) for o in validation.as_array(offsets_h, "offsets_h", ndim=(1,), min_size=1))
    n_repeats = validation.integer(n_repeats, "n_repeats", minimum=1)
    validation.int_seed_list(seed, "seed", why="repeats append an index")
    q_base_km2_s3 = validation.positive(q_base_km2_s3, "q_base_km2_s3")
    window_hours = validation.positive(window_hours, "window_hours")
    _check_executor(executor)
    dirs = np.radians(np.array(list(DIRECTIONS.values())))
    make_setup = _setup_maker(system)
    setups = {(f, s): make_setup(orbit, f * det.window_control_weight(det.ACTIVE_POLICY, window_hours), q_base_km2_s3,
                                 window_hours=window_hours, sigma_angle_rad=s * 1e-6)
              for f in f_values for s in noise_urad}
    # the trials depend on the noise and the burn time, not on f: drawn once, filtered under every f, all cells
    # pooled in lockstep groups (detection.direction_response per cell gives the same numbers)
    trials = {(s, off): det.direction_trials(setups[f_values[0], s], dirs, 1.0, n_repeats, seed, burn_offset_hours=off)
              for s in noise_urad for off in offsets_h}
    keys = [(f, s, off) for f in f_values for s in noise_urad for off in offsets_h]
    results = det.filter_trial_sets([(setups[f, s], trials[s, off]) for f, s, off in keys], executor=executor)
    cells = {}
    for (f, s, off), res in zip(keys, results):
        zs = (res.z_smooth * system.velocity_unit_km_s * 1e3).reshape(n_repeats, len(dirs)).mean(0)
        cells[f, s, off] = (zs, zs[2:4].mean() / np.r_[zs[:2], zs[4:]].mean())
    setup = setups[f_values[-1], noise_urad[-1]]
    sc = setup.scenario
    truth = tracking.simulate_truth(system, sc.x_start, sc.t, [])
    k_apo = int(np.argmin(np.abs(sc.t - setup.t_maneuver)))
    los = truth[k_apo, :3] - setup.observer_states[k_apo, :3]
    return PmJSearch(cells, tuple(f_values), tuple(offsets_h), los / np.linalg.norm(los),
                     float(np.linalg.norm(los) * system.length_unit_km))


# ---------------------------------------------------------------------------------------------------------------
# Health metric (Fig. 22)
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BurnZStudy:
    """z of the same randomly pointed burns of one size under the quiet window tuning at several factors.

    Attributes
    ----------
    z : dict
        f -> z of every run, m/s.
    magnitude_m_s : float
    """

    z: dict
    magnitude_m_s: float

    def sigma_level(self, f: float, h1_z) -> float:
        """(mean z at ``f`` - mean of ``h1_z``) / sd of ``h1_z``."""
        h1_z = np.asarray(h1_z)
        return float((self.z[f].mean() - h1_z.mean()) / h1_z.std())

    def report(self) -> str:
        return "\n".join(f"f = {f:4.2f}: z of a {self.magnitude_m_s:g} m/s burn {z.mean():.4f} +- {z.std(ddof=1):.4f} m/s "
                         f"(mean +- single-run sd, {z.size} runs), range {z.min():.3f}-{z.max():.3f}"
                         for f, z in self.z.items())


def run_burn_z_study(setup: det.DetectionSetup, orbit, factors, magnitude_m_s: float, n: int, seed, *,
                     q_base_km2_s3: float, window_hours: float, executor=None) -> BurnZStudy:
    """Draw ``n`` burns of ``magnitude_m_s`` on ``setup`` (seed ``seed``, spawned per run) and filter them with the quiet
    window tuning at each factor of ``factors`` (sorted; all factors pooled in lockstep groups, through ``executor``
    when given)."""
    _check_setup(setup)
    _check_orbit(orbit)
    _positive_values(factors, "factors")
    magnitude_m_s = validation.positive(magnitude_m_s, "magnitude_m_s")
    n = validation.integer(n, "n", minimum=1)
    validation.seed_entropy(seed, "seed")
    q_base_km2_s3 = validation.positive(q_base_km2_s3, "q_base_km2_s3")
    window_hours = validation.positive(window_hours, "window_hours")
    _check_executor(executor)
    runs = det.draw_trials(np.random.default_rng(seed).spawn(n), setup, magnitude_m_s=magnitude_m_s)
    fs = sorted(set(factors))
    make_setup = _setup_maker(setup.system)
    tunings = [make_setup(orbit, f * det.window_control_weight(det.QUIET_POLICY, window_hours), q_base_km2_s3,
                          window_hours=window_hours) for f in fs]
    results = det.filter_trial_sets([(s, runs) for s in tunings], executor=executor)
    z = {f: r.z_smooth * setup.system.velocity_unit_km_s * 1e3 for f, r in zip(fs, results)}
    return BurnZStudy(z, float(magnitude_m_s))


def lead_report(lead: dict, n_h0: int) -> str:
    """The control-versus-residual race per setting (``lead``: label -> detection.HealthLeadStudy), as text."""
    validation.dict_of(lead, "lead", det.HealthLeadStudy, "detection.HealthLeadStudy")
    n_h0 = validation.integer(n_h0, "n_h0", minimum=1)
    lines = []
    for tag, h in lead.items():
        fr = h.outcome_fractions()
        mc, mr = h.median_delay_hours("control"), h.median_delay_hours("residual")
        lines.append(f"{tag}: false alarms over 24 h: control {100 * h.false_alarm_control:.1f} %, residual "
                     f"{100 * h.false_alarm_residual:.1f} % ({n_h0} no-burn runs)")
        for m, mag in enumerate(h.magnitudes_m_s):
            lines.append(
                f"   {mag:4.2f} m/s: control first {100 * fr['control first'][m]:3.0f} %, same epoch "
                f"{100 * fr['same epoch'][m]:3.0f} %, residual first {100 * fr['residual first'][m]:3.0f} %, neither "
                f"{100 * fr['neither'][m]:3.0f} % | median delay control "
                f"{(f'{mc[m]:4.1f} h' if np.isfinite(mc[m]) else 'none (never detected)')}, residual "
                f"{(f'{mr[m]:4.1f} h' if np.isfinite(mr[m]) else 'none (never detected)')} | "
                f"z over the whole track {np.median(h.z_final_m_s[m]):.4f} m/s (median)")
    return "\n".join(lines)


def lead_reading(lead: dict) -> str:
    """Where the control test is first in most runs, and the 0.5 m/s race, per setting (text)."""
    validation.dict_of(lead, "lead", det.HealthLeadStudy, "detection.HealthLeadStudy")
    lines = []
    for tag, h in lead.items():
        fr = h.outcome_fractions()
        sizes = [f"{m:g}" for m, c in zip(h.magnitudes_m_s, fr["control first"]) if c > 0.5]
        i5 = int(np.argmin(np.abs(h.magnitudes_m_s - 0.5)))
        lines.append(f"{tag}: control strictly first in most runs at {', '.join(sizes) or 'no'} m/s; for 0.5 m/s the "
                     f"residual test fires first or at the same epoch in "
                     f"{100 * (fr['residual first'][i5] + fr['same epoch'][i5]):.0f} % of the runs, neither fires "
                     f"within 24 h in {100 * fr['neither'][i5]:.0f} %")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------------------------
# Thresholds and consistency together: the joint search over window, base weight, noise and burn time (issue 23)
# ---------------------------------------------------------------------------------------------------------------

#: Relative band around the paper's thresholds for the joint search (the threshold reading's 25 %, fixed before
#: the search was run).
JOINT_ZLIM_TOL = 0.25
#: The screen's wider z_lim band (its small Monte Carlo must not drop a setting the paper-size one would keep).
JOINT_SCREEN_ZLIM_TOL = 0.40


@dataclass(frozen=True)
class JointSearch:
    """Reduced screen and paper-size confirmation of the unstated detection tuning, 9:2 NRHO, both policies.

    A setting is ``(window_hours, f, q_base_km2_s3, noise_urad, burn_offset_hours)``: the window weight is ``f``
    times the policy's variance-matched weight for that window (:func:`detection.window_control_weight`), the burn
    is ``burn_offset_hours`` after the apoapsis (inside the window, which stays centred on the apoapsis).

    Criteria, fixed before the search was run.  *Screen* (small Monte Carlo): for both policies z_lim within
    :data:`JOINT_SCREEN_ZLIM_TOL` of the paper's and the worst cell (H0/H1, forward/smoothed) at most
    :data:`CONSISTENT_FRACTION` plus two binomial standard errors of the screen's runs.  *Confirmation* (paper-size
    Monte Carlo, every setting that passed the screen): for both policies z_lim within :data:`JOINT_ZLIM_TOL` of the
    paper's and the worst cell at most :data:`CONSISTENT_FRACTION`.

    Attributes
    ----------
    screen : dict
        Setting -> {policy -> dict(``z_lim`` [m/s], ``worst`` (largest fraction of inconsistent runs), ``n`` (H0,
        H1 runs))}.
    confirm : dict
        Setting that passed the screen -> {policy -> dict(``z_lim`` [m/s], ``z_lim_se`` (bootstrap standard error,
        m/s), ``worst``, ``h1`` (inconsistent burn runs, forward and smoothed), ``err`` (FP + MD), ``n``)}.
    paper_zlim : dict
        Policy -> the paper's threshold, m/s.
    n_screen, n_paper : (int, int)
        H0 and H1 runs per policy of the screen and of the confirmation.
    n_boot : int
        Bootstrap resamples of each confirmed threshold.
    """

    screen: dict
    confirm: dict
    paper_zlim: dict
    n_screen: tuple
    n_paper: tuple
    n_boot: int

    @property
    def policies(self) -> tuple:
        return tuple(self.paper_zlim)

    @property
    def screen_limit(self) -> float:
        """Largest fraction of inconsistent runs a screened setting may show (10 % plus two binomial standard errors
        of a fraction of the screen's H1 runs)."""
        return CONSISTENT_FRACTION + 2 * fraction_standard_error(CONSISTENT_FRACTION, self.n_screen[1])

    def _ok(self, cells: dict, tol: float, limit: float) -> bool:
        return all(abs(cells[p]["z_lim"] / self.paper_zlim[p] - 1) <= tol and cells[p]["worst"] <= limit
                   for p in self.policies)

    @property
    def screen_passed(self) -> list:
        """Settings that passed the screen (in the screen's order)."""
        return [k for k, c in self.screen.items() if self._ok(c, JOINT_SCREEN_ZLIM_TOL, self.screen_limit)]

    @property
    def passed(self) -> list:
        """Settings whose paper-size Monte Carlo meets both criteria (thresholds within 25 %, at most 10 %
        inconsistent runs in every cell), both policies."""
        return [k for k, c in self.confirm.items() if self._ok(c, JOINT_ZLIM_TOL, CONSISTENT_FRACTION)]

    @property
    def any_8h(self) -> bool:
        """Does any setting with the paper's 8-hour window satisfy both criteria at paper size?"""
        return any(k[0] == 8.0 for k in self.passed)

    def windows_passed(self) -> list:
        return sorted({k[0] for k in self.passed})

    def best_8h(self):
        """The 8-h setting (screened) closest to both criteria: (setting, its worst cell over policies, its largest
        relative z_lim deviation), choosing among consistent ones the smallest deviation (None if no 8-h setting)."""
        rows = [(k, max(c[p]["worst"] for p in self.policies),
                 max(abs(c[p]["z_lim"] / self.paper_zlim[p] - 1) for p in self.policies))
                for k, c in self.screen.items() if k[0] == 8.0]
        if not rows:
            return None
        ok = [r for r in rows if r[1] <= self.screen_limit]
        return min(ok, key=lambda r: r[2]) if ok else min(rows, key=lambda r: r[1])

    @staticmethod
    def label(key) -> str:
        w, f, qb, s, off = key
        return f"{w:g} h, f = {f:g}, q_b = {qb:.0e}, {s:g} urad, burn {off:+g} h"

    def report(self) -> str:
        n_s = len(self.screen)
        lines = [f"screen: {n_s} settings x {len(self.policies)} policies, {self.n_screen[0]} + {self.n_screen[1]} "
                 f"runs each; passed (z_lim within {100 * JOINT_SCREEN_ZLIM_TOL:.0f} %, worst cell <= "
                 f"{100 * self.screen_limit:.1f} %): {len(self.screen_passed)}"]
        b = self.best_8h()
        if b is not None:
            lines.append(f"closest 8-h setting of the screen: {self.label(b[0])} (worst cell {100 * b[1]:.1f} %, "
                         f"largest z_lim deviation {100 * b[2]:.0f} %)")
        lines.append(f"paper-size confirmation ({self.n_paper[0]} + {self.n_paper[1]} runs per policy, "
                     f"{self.n_boot} bootstrap resamples): z_lim +- se (deviation from the paper), worst cell")
        for k, c in self.confirm.items():
            lines.append(f"  {self.label(k)}: " + "; ".join(
                f"{p} {c[p]['z_lim'] * 1e3:.2f} +- {c[p]['z_lim_se'] * 1e3:.2f} mm/s "
                f"({100 * (c[p]['z_lim'] / self.paper_zlim[p] - 1):+.0f} %, "
                f"{(c[p]['z_lim'] - self.paper_zlim[p]) / max(c[p]['z_lim_se'], 1e-300):+.1f} se), worst "
                f"{100 * c[p]['worst']:.1f} %" for p in self.policies)
                + ("  -> both hold" if k in self.passed else ""))
        lines.append(f"settings meeting both criteria at paper size: {len(self.passed)} (windows "
                     f"{self.windows_passed() or 'none'}); any with the paper's 8-h window: "
                     f"{'yes' if self.any_8h else 'no'}")
        return "\n".join(lines)


def _joint_setups(system, orbit, policies, key, make_setup=None):
    w, f, qb, s, off = key
    make_setup = make_setup or _setup_maker(system)  # a maker shared across settings builds each track once
    out = {}
    for p, pol in policies.items():
        st = make_setup(orbit, f * det.window_control_weight(pol, w), qb, window_hours=w, sigma_angle_rad=s * 1e-6)
        if off:  # the burn moves, the window stays centred on the apoapsis
            st = dataclasses.replace(st, t_maneuver=st.t_maneuver + off * 3600.0 / system.time_unit_s)
        out[p] = st
    return out


def _joint_cell(st: det.PolicyStudy) -> dict:
    return {"z_lim": float(st.threshold.z_lim), "worst": float(max(*st.h0.inconsistent_runs,
                                                                  *st.h1.inconsistent_runs)),
            "h1": st.h1.inconsistent_runs, "err": float(st.threshold.total_error), "n": (len(st.h0), len(st.h1))}


def run_joint_search(system, orbit, policies: dict, windows_hours, factors, q_bases_km2_s3, noise_urad,
                     burn_offsets_hours, n_screen, n_paper, n_boot: int, seed, *, paper_zlim: dict,
                     batch_size: int = 8, executor=None, screened: JointSearch | None = None,
                     confirm_windows=None) -> JointSearch:
    """Joint search for a tuning at which the paper's thresholds and its consistency claim hold together.

    Every combination of ``windows_hours`` x ``factors`` x ``q_bases_km2_s3`` x ``noise_urad`` x
    ``burn_offsets_hours`` (offsets outside the half window are skipped) is screened with ``n_screen`` runs per
    policy; every setting that passes the screen (:class:`JointSearch`) is rerun with ``n_paper`` runs (the paper's
    500 + 3000) and its thresholds bootstrapped ``n_boot`` times.  Setting ``i`` of the screen uses the seeds
    ``[*seed, 0, i, j]`` (policy ``j``), its confirmation ``[*seed, 1, i, j]`` and its bootstrap ``[*seed, 2, i, j]``;
    all Monte Carlo of a stage go through :func:`detection.run_policy_studies` in one pooled sweep, so the result is
    bit-identical whatever ``executor`` runs it.

    Parameters
    ----------
    system : CR3BP
    orbit : PeriodicOrbit
        The target orbit (the paper's thresholds are the 9:2 NRHO's).
    policies : dict
        Name -> detection.StationKeepingPolicy; every name must have a threshold in ``paper_zlim``.
    windows_hours : sequence of float
        Window lengths, hours.
    factors : sequence of float
        Window weight factors f (units of :func:`detection.window_control_weight` for each window).
    q_bases_km2_s3 : sequence of float
        Base weights outside the window, km^2/s^3.
    noise_urad : sequence of float
        Angle noise (1 sigma), micro-rad.
    burn_offsets_hours : sequence of float
        Burn times after the apoapsis, hours.
    n_screen, n_paper : (int, int)
        H0 and H1 training runs per policy of the screen and of the confirmation (at least 2 each).
    n_boot : int
        Bootstrap resamples of each confirmed threshold (at least 2).
    seed : int or sequence of int
    paper_zlim : dict
        Policy -> the paper's threshold, m/s.
    batch_size : int
        Trials per lockstep batch (at least 1).
    executor : concurrent.futures-style executor or Dask Client, optional
    screened : JointSearch, optional
        An earlier result of this function with the same grid, screen size and seed: its screen is reused (the
        screen's numbers do not depend on ``n_paper`` or ``n_boot``) and only the confirmation runs.
    confirm_windows : sequence of float, optional
        Confirm only the passing settings with these windows (default: all; empty: the screen only).  The seeds do
        not change, so the confirmations of runs with disjoint ``confirm_windows`` merge into those of one run with
        all of them.

    Returns
    -------
    JointSearch
    """
    check_system(system)
    _check_orbit(orbit)
    validation.dict_of(policies, "policies", det.StationKeepingPolicy, "detection.StationKeepingPolicy")
    validation.instance(paper_zlim, "paper_zlim", dict, "a dict policy -> threshold (m/s)")
    for p in policies:
        if p not in paper_zlim:
            raise ValueError(f"paper_zlim must give a threshold for every policy; missing {p!r}")
        validation.positive(paper_zlim[p], f"paper_zlim[{p!r}]")
    windows = tuple(float(w) for w in _positive_values(windows_hours, "windows_hours"))
    factors = tuple(float(f) for f in _positive_values(factors, "factors"))
    q_bases = tuple(float(q) for q in _positive_values(q_bases_km2_s3, "q_bases_km2_s3"))
    noises = tuple(float(s) for s in _positive_values(noise_urad, "noise_urad"))
    offsets = tuple(float(o) for o in validation.as_array(burn_offsets_hours, "burn_offsets_hours", ndim=(1,),
                                                            min_size=1))
    sizes = []
    for name, n in (("n_screen", n_screen), ("n_paper", n_paper)):
        validation.instance(n, name, (tuple, list, np.ndarray), "a pair (H0 runs, H1 runs)")
        if len(n) != 2:
            raise ValueError(f"{name} must be a pair (H0 runs, H1 runs); got {n!r}")
        sizes.append(tuple(validation.integer(k, name, minimum=2) for k in n))
    n_boot = validation.integer(n_boot, "n_boot", minimum=2)
    seed = validation.int_seed_list(seed, "seed", why="the stages append an index")
    batch_size = validation.integer(batch_size, "batch_size", minimum=1)
    _check_executor(executor)
    keys = [(w, f, qb, s, off) for w in windows for f in factors for qb in q_bases for s in noises for off in offsets
            if abs(off) <= w / 2]
    if not keys:
        raise ValueError(f"burn_offsets_hours must hold an offset inside some window (|offset| <= window / 2); got "
                         f"{offsets} for windows {windows}")
    make_setup = _setup_maker(system)
    setups = {k: _joint_setups(system, orbit, policies, k, make_setup) for k in keys}
    pnames = tuple(policies)

    def stage(chosen, n, tag):
        jobs = [(setups[k][p], policies[p], *n, 0, [*seed, tag, keys.index(k), j]) for k in chosen
                for j, p in enumerate(pnames)]
        done = iter(det.run_policy_studies(jobs, batch_size=batch_size, executor=executor))
        return {k: {p: next(done) for p in pnames} for k in chosen}

    if screened is not None:
        validation.instance(screened, "screened", JointSearch)
        if list(screened.screen) != keys or tuple(screened.n_screen) != sizes[0] or screened.policies != pnames:
            raise ValueError("screened must come from the same grid, policies and screen size (its screen is reused)")
        screen = screened.screen
    else:
        screen = {k: {p: _joint_cell(st) for p, st in c.items()} for k, c in stage(keys, sizes[0], 0).items()}
    zlim = {p: float(paper_zlim[p]) for p in pnames}
    draft = JointSearch(screen, {}, zlim, sizes[0], sizes[1], n_boot)
    confirm = {}
    chosen = draft.screen_passed
    if confirm_windows is not None:  # an empty sequence runs the screen only
        wanted = {float(w) for w in validation.as_array(confirm_windows, "confirm_windows", ndim=(1,))}
        chosen = [k for k in chosen if k[0] in wanted]
    confirmed = stage(chosen, sizes[1], 1)
    where = [(k, p, st) for k, c in confirmed.items() for p, st in c.items()]
    boots = iter(_bootstraps([(st.h0.z, st.h1.z, n_boot, [*seed, 2, keys.index(k), pnames.index(p)])
                              for k, p, st in where], executor))
    for k, p, st in where:
        confirm.setdefault(k, {})[p] = dict(_joint_cell(st), z_lim_se=float(next(boots)[:, 0].std(ddof=1)))
    return JointSearch(screen, confirm, zlim, sizes[0], sizes[1], n_boot)


# ---------------------------------------------------------------------------------------------------------------
# The Fig. 22 race over angle noise and window weight
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class LeadGrid:
    """The control-versus-residual race (:func:`detection.health_lead_study`) of an unexpected burn over the quiet
    window weight factor f and the angle noise (Fig. 22).

    The paper's combination, judged per cell with criteria fixed before the grid was run: the residuals stay benign
    (the residual test silent over the horizon in more than half of the Fig. 22-size runs), the control test fires
    (within the horizon in more than half of them) and strictly first in more than half, and z recovers the burn
    (median z over the whole track at least half the burn size).

    Attributes
    ----------
    cells : dict
        (f, noise [micro-rad]) -> detection.HealthLeadStudy.
    magnitude_m_s : float
        The burn size judged (Fig. 22: 0.5 m/s).
    """

    cells: dict
    magnitude_m_s: float

    def _i(self, h) -> int:
        return int(np.argmin(np.abs(h.magnitudes_m_s - self.magnitude_m_s)))

    def summary(self, key) -> dict:
        """``residual_silent``, ``control_fires``, ``control_first`` (fractions of the runs at the judged size),
        ``z_ratio`` (median z over the burn) and ``holds`` (the paper's combination)."""
        h = self.cells[key]
        i = self._i(h)
        fr = h.outcome_fractions()
        d = dict(residual_silent=float(np.mean(h.residual_epoch[i] < 0)),
                 control_fires=float(np.mean(h.control_epoch[i] >= 0)), control_first=float(fr["control first"][i]),
                 z_ratio=float(np.median(h.z_final_m_s[i]) / self.magnitude_m_s),
                 false_alarm=(h.false_alarm_control, h.false_alarm_residual))
        d["holds"] = bool(d["residual_silent"] > 0.5 and d["control_fires"] > 0.5 and d["control_first"] > 0.5
                          and d["z_ratio"] >= 0.5)
        return d

    @property
    def holding(self) -> list:
        """Cells where the paper's combination holds."""
        return [k for k in self.cells if self.summary(k)["holds"]]

    def report(self) -> str:
        lines = [f"race at {self.magnitude_m_s:g} m/s per (f, noise): residual test silent for the horizon / control "
                 "test fires / control strictly first (fractions of runs), median z over the burn, false alarms "
                 "control / residual"]
        for k in self.cells:
            s = self.summary(k)
            lines.append(f"  f = {k[0]:4.2f}, {k[1]:4.0f} urad: {100 * s['residual_silent']:3.0f} % / "
                         f"{100 * s['control_fires']:3.0f} % / {100 * s['control_first']:3.0f} %, z/burn "
                         f"{s['z_ratio']:.2f}, false alarms {100 * s['false_alarm'][0]:.1f} % / "
                         f"{100 * s['false_alarm'][1]:.1f} %" + ("  -> paper's combination" if s["holds"] else ""))
        lines.append("cells with benign residuals, a fast control test and z near the burn: "
                     + (", ".join(f"f = {f:g}, {s:g} urad" for f, s in self.holding) or "none"))
        return "\n".join(lines)


def run_lead_grid(system, orbit, factors, noise_urad, magnitudes_m_s, n_h0: int, n_h1: int, seed, *,
                  q_base_km2_s3: float, window_hours: float, judged_m_s: float = 0.5, horizon_hours: float = 24.0,
                  executor=None) -> LeadGrid:
    """:func:`detection.health_lead_study` at the quiet window tuning for every factor of ``factors`` and angle noise
    of ``noise_urad`` (micro-rad); cell ``i`` (factors outer, noise inner) uses the seed ``[*seed, i]``.  The
    result does not depend on ``executor``."""
    check_system(system)
    _check_orbit(orbit)
    factors = tuple(float(f) for f in _positive_values(factors, "factors"))
    noises = tuple(float(s) for s in _positive_values(noise_urad, "noise_urad"))
    mags = _positive_values(magnitudes_m_s, "magnitudes_m_s")
    judged = validation.positive(judged_m_s, "judged_m_s")
    if not np.any(np.isclose(mags, judged)):
        raise ValueError(f"magnitudes_m_s must contain judged_m_s = {judged:g}; got {mags}")
    n_h0 = validation.integer(n_h0, "n_h0", minimum=10)
    n_h1 = validation.integer(n_h1, "n_h1", minimum=1)
    seed = validation.int_seed_list(seed, "seed", why="each cell appends its index")
    q_base_km2_s3 = validation.positive(q_base_km2_s3, "q_base_km2_s3")
    window_hours = validation.positive(window_hours, "window_hours")
    horizon_hours = validation.positive(horizon_hours, "horizon_hours")
    _check_executor(executor)
    cells = {}
    make_setup = _setup_maker(system)
    for i, (f, s) in enumerate((f, s) for f in factors for s in noises):
        st = make_setup(orbit, f * det.window_control_weight(det.QUIET_POLICY, window_hours), q_base_km2_s3,
                        window_hours=window_hours, sigma_angle_rad=s * 1e-6)
        cells[f, s] = det.health_lead_study(st, mags, n_h0, n_h1, [*seed, i], horizon_hours=horizon_hours,
                                            executor=executor)
    return LeadGrid(cells, float(judged))


# ---------------------------------------------------------------------------------------------------------------
# The closing table's measurements
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class HealthRuns:
    """Fig. 22 read run by run: for each burn the paper's two panels as numbers (notebook 10, Section 6).

    A run shows the paper's combination, a diverging estimate with benign residuals, when its mean smoothed NEES
    exceeds :data:`HEALTH_NEES_DIVERGED` (6 for a consistent filter) while the residual test of the race
    (:func:`cislunar.papers.greaves_scheeres_2021.detection.health_lead_study`: a squared whitened residual above the
    upper 3-sigma tail, 0.135 %, of its chi-square law) stays silent at every epoch of the 24 hours after the burn.
    The median whitened residual norm over the whole track (the test first applied to the figure's single run, below
    :data:`HEALTH_RESIDUAL_BENIGN`) is kept as the lenient reading: it mixes the epochs before the burn with those after.

    Attributes
    ----------
    nees_mean : ndarray, shape (R,)
        Per run, the mean smoothed NEES over the epochs (dimensionless).
    residual_silent : ndarray of bool, shape (R,)
        Per run, whether the residual test stays silent over the horizon after the burn.
    residual_median : ndarray, shape (R,)
        Per run, the median whitened residual norm over all epochs (dimensionless).
    """

    nees_mean: np.ndarray
    residual_silent: np.ndarray
    residual_median: np.ndarray

    def __post_init__(self):
        a = validation.as_array(self.nees_mean, "nees_mean", ndim=(1,), min_size=1)
        m = validation.as_array(self.residual_median, "residual_median", shape=a.shape)
        q = np.asarray(self.residual_silent)
        if q.dtype != bool or q.shape != a.shape:
            raise ValueError(f"residual_silent must be a bool array of shape {a.shape}; got {q.dtype} {q.shape}")
        if np.any(a < 0) or np.any(m < 0):
            raise ValueError("nees_mean and residual_median must be non-negative")
        object.__setattr__(self, "nees_mean", a)
        object.__setattr__(self, "residual_median", m)
        object.__setattr__(self, "residual_silent", q)

    @classmethod
    def from_filter(cls, setup: det.DetectionSetup, inputs, result, *, horizon_hours: float = 24.0,
                    tail_probability: float = float(stats.norm.sf(3.0))) -> "HealthRuns":
        """From trials drawn on ``setup`` (detection.draw_trials) and their batched OCBE (detection.filter_trials or
        filter_trial_sets on the same trials).  The residual test looks at the epochs within ``horizon_hours`` after
        the burn (``setup.t_maneuver``), at the per-epoch tail ``tail_probability`` (the race's)."""
        _check_setup(setup)
        inputs = validation.sequence_of(inputs, "inputs", det.TrialInputs, "detection.TrialInputs (detection.draw_trials)")
        validation.instance(result, "result", BatchOCBEResult,
                            "a cislunar.estimation.batched_ocbe.BatchOCBEResult (detection.filter_trials)")
        shape = (len(inputs), setup.scenario.t.size)
        if result.x_smooth is None or result.x_smooth.shape[:2] != shape or result.residual_norms.shape != shape:
            raise ValueError(f"result must be the smoothed OCBE of the {len(inputs)} trials of inputs over the "
                             f"{shape[1]} epochs of setup")
        horizon_hours = validation.positive(horizon_hours, "horizon_hours")
        p = validation.in_range(tail_probability, "tail_probability", 0.0, 0.5, closed=False)
        sc = setup.scenario
        hours = (sc.t - setup.t_maneuver) * setup.system.time_unit_s / 3600.0
        window = (hours > 0) & (hours <= horizon_hours)
        limit = float(np.sqrt(stats.chi2.isf(p, sc.model.dim)))
        nees_mean = [float(nees(result.x_smooth[b], result.P_smooth[b], i.truth).mean()) for b, i in enumerate(inputs)]
        silent = ~np.any(result.residual_norms[:, window] > limit, axis=1)
        return cls(np.array(nees_mean), silent, np.median(result.residual_norms, axis=1))

    @classmethod
    def pooled(cls, runs) -> "HealthRuns":
        """The runs of several sets (a sequence of HealthRuns) as one set."""
        runs = list(runs)
        if not runs:
            raise ValueError("runs must hold at least one HealthRuns")
        for r in runs:
            validation.instance(r, "runs", HealthRuns)
        return cls(*(np.concatenate([getattr(r, f.name) for r in runs]) for f in dataclasses.fields(cls)))

    def __len__(self) -> int:
        return self.nees_mean.size

    @property
    def diverged(self) -> np.ndarray:
        return self.nees_mean > HEALTH_NEES_DIVERGED

    @property
    def benign_while_diverging(self) -> np.ndarray:
        """Per run: does it show the paper's combination (diverging estimate, silent residual test)?"""
        return self.diverged & self.residual_silent

    @property
    def share(self) -> float:
        """Fraction of the runs showing the combination."""
        return float(np.mean(self.benign_while_diverging))

    @property
    def lenient_share(self) -> float:
        """The same with the lenient reading of benign residuals (whole-track median below
        :data:`HEALTH_RESIDUAL_BENIGN`)."""
        return float(np.mean(self.diverged & (self.residual_median < HEALTH_RESIDUAL_BENIGN)))

    @property
    def floor_standard_error(self) -> float:
        """Binomial standard error of a share at the plausibility floor (:data:`HEALTH_PLAUSIBLE_FLOOR`) over these
        runs: the Fig. 22 row holds when :attr:`share` is at least the floor less two of these."""
        return fraction_standard_error(HEALTH_PLAUSIBLE_FLOOR, len(self))

    @property
    def floor_probability(self) -> float:
        """Exact binomial probability of at most our number of runs with the combination if its true share were the
        floor (one-sided)."""
        return float(stats.binom.cdf(int(self.benign_while_diverging.sum()), len(self), HEALTH_PLAUSIBLE_FLOOR))

    def text(self) -> str:
        """The per-run reading in words."""
        return (f"{int(self.benign_while_diverging.sum())} of {len(self)} runs ({100 * self.share:.1f} %; exact "
                f"binomial P(at most that many | {100 * HEALTH_PLAUSIBLE_FLOOR:g} %) = {self.floor_probability:.3f}); "
                f"diverging (NEES mean > {HEALTH_NEES_DIVERGED:g}) {100 * self.diverged.mean():.0f} %, residual test "
                f"silent for 24 h {100 * self.residual_silent.mean():.0f} %; lenient reading (whole-track residual "
                f"median < {HEALTH_RESIDUAL_BENIGN:g}, half the epochs before the burn): {100 * self.lenient_share:.0f} %")


def closing_rows(*, ks_text: str, tmap: TuningMap, f_tune: float, q_window_quiet, counts: dict, spike: SpikeStudy,
                 train: TrainingStudies, pm_j: PmJSearch, pm_mc: dict, burn_z: BurnZStudy, sig_level: dict,
                 lead: dict, health_nees_mean: float, health_residual_norms, sigma_angle_rad: float,
                 joint: JointSearch | None = None, lead_grid: LeadGrid | None = None,
                 health_runs: dict | None = None) -> dict:
    """The measured value of each row of notebook 10's closing table, keyed as
    :data:`cislunar.papers.greaves_scheeres_2021.claims.maneuver_detection.CLAIMS`, in the table's order: each value
    is the keyword arguments of :meth:`Claim.judge` (``measured``, ``shown``, ``note``, ``standard_error`` for the
    Monte Carlo tolerances, ``reason`` where it depends on the run).

    Parameters
    ----------
    ks_text : str
        KS p-value of the pointing against a uniform sphere, as printed.
    tmap : TuningMap
        Gives f_c, the threshold-matching factors and the settings.
    f_tune : float
        The threshold reading's factor (0.1).
    q_window_quiet : (float, float)
        Quiet window weight of the 9:2 NRHO at f = 0.1 and at f_c, km^2/s^3.
    counts : dict
        Sizes: ``n_h0``, ``n_h1``, ``n_test``, ``outer_sizes``, ``n_spike``, ``n_z05``, ``n_lead`` (no-burn, per
        size), ``n_pm_j_mc``, ``pm_j_seeds``.
    spike, train, pm_j, burn_z : the studies of Sections 2-6
    pm_mc : dict
        Policy -> detection.MonteCarloSample of random burns in the +-j regime.
    sig_level : dict
        Tag -> sigma level of the 0.5 m/s burns among the quiet H1 training runs.
    lead : dict
        Label -> detection.HealthLeadStudy (the labels of notebook 10; the f_c one starts with "f_c").
    health_nees_mean, health_residual_norms
        The single Fig. 22 run: its mean smoothed NEES and its whitened residual norms.
    sigma_angle_rad : float
        Our angle noise.
    joint : JointSearch, optional
        The joint search over window, f, base weight, noise and burn time (:func:`run_joint_search`); its two rows
        are measured only when given (notebook 10 gives it: its table must judge every declared claim).
    lead_grid : LeadGrid, optional
        The Fig. 22 race over f and the angle noise (:func:`run_lead_grid`); its row only when given.
    health_runs : dict, optional
        Tag (:data:`TAGS`) -> :class:`HealthRuns` of the 0.5 m/s burns at our noise: the Fig. 22 row (residuals
        benign while the estimate diverges) is judged over all of them, pooled, and measured only when given
        (notebook 10 gives it).
    """
    validation.instance(ks_text, "ks_text", str)
    validation.instance(tmap, "tmap", TuningMap)
    f_tune = validation.positive(f_tune, "f_tune")
    q_window_quiet = validation.as_array(q_window_quiet, "q_window_quiet", shape=(2,))
    if np.any(q_window_quiet <= 0):
        raise ValueError(f"q_window_quiet must be two positive weights (km^2/s^3); got {q_window_quiet}")
    validation.instance(counts, "counts", dict)
    missing = {"n_h0", "n_h1", "n_test", "outer_sizes", "n_spike", "n_z05", "n_lead", "n_pm_j_mc",
               "pm_j_seeds"} - set(counts)
    if missing:
        raise ValueError(f"counts must give every size; missing {sorted(missing)}")
    validation.instance(spike, "spike", SpikeStudy)
    validation.instance(train, "train", TrainingStudies)
    validation.instance(pm_j, "pm_j", PmJSearch)
    validation.dict_of(pm_mc, "pm_mc", det.MonteCarloSample, "detection.MonteCarloSample")
    if not {"active", "quiet"} <= set(pm_mc):
        raise ValueError(f"pm_mc must hold the 'active' and 'quiet' samples; got {list(pm_mc)}")
    validation.instance(burn_z, "burn_z", BurnZStudy)
    validation.instance(sig_level, "sig_level", dict)
    if set(sig_level) != set(TAGS):
        raise ValueError(f"sig_level must give a sigma level per tag {TAGS}; got {list(sig_level)}")
    for tag in TAGS:
        validation.real(sig_level[tag], f"sig_level[{tag!r}]")
    validation.dict_of(lead, "lead", det.HealthLeadStudy, "detection.HealthLeadStudy")
    health_nees_mean = validation.real(health_nees_mean, "health_nees_mean")
    validation.as_array(health_residual_norms, "health_residual_norms", ndim=(1,), min_size=1)
    sigma_angle_rad = validation.positive(sigma_angle_rad, "sigma_angle_rad")
    if joint is not None:
        validation.instance(joint, "joint", JointSearch)
    if lead_grid is not None:
        validation.instance(lead_grid, "lead_grid", LeadGrid)
    if health_runs is not None:
        validation.dict_of(health_runs, "health_runs", HealthRuns, "HealthRuns")
        if not health_runs or not set(health_runs) <= set(TAGS):
            raise ValueError(f"health_runs must map tags among {TAGS} to HealthRuns; got {list(health_runs)}")
    F_C, F_TUNE, F_GRID, F_SIDE = tmap.f_c, f_tune, tmap.f_grid, tmap.f_side
    VARIANTS, POLICIES, ORBITS, STABLE = tmap.variants, tmap.policies, tmap.orbits, tmap.orbits[1:]
    F_MATCH = {p: tmap.f_match(p) for p in POLICIES}
    N_H0, N_H1, N_TEST = counts["n_h0"], counts["n_h1"], counts["n_test"]
    N_SPIKE, N_Z05, N_LEAD = counts["n_spike"], counts["n_z05"], counts["n_lead"]
    N_PM_J_MC, PM_J_SEEDS = counts["n_pm_j_mc"], counts["pm_j_seeds"]
    studies, studies_c, se, nees_rows, lin = train.tuned, train.predicted, train.se, train.nees_rows, train.lin
    acc = {(k, t): train.accuracy(k, t) for t in TAGS for k in train.studies[t]}
    spike_limit = spike.fig10_limit
    spike, fig10_ok, fig11_h1, fig11_h0 = spike.cells, spike.fig10_ok, spike.fig11_h1, spike.fig11_h0
    (f_pm, sig_pm, _), _ = pm_j.best
    z05 = burn_z.z
    rows = {}
    rows["magnitude bounds"] = dict(measured="yes (exact truncnorm draws)")
    rows["pointing"] = dict(measured=f"as written; not uniform on the sphere (KS p {ks_text})",
                         note="uniform elevation over-weights the poles; implemented as the paper writes it")
    rows["noise"] = dict(measured="10 micro-rad angles; rates sqrt(2)*10 micro-rad/s")
    rows["tuning"] = dict(measured=f"q_w = f E[u^2]/(3T), base 1e-18 km^2/s^3; f_c = {F_C:g} (consistency reading), "
                       f"f = {F_TUNE:g} (threshold reading): quiet q_w {q_window_quiet[1]:.2e} / "
                       f"{q_window_quiet[0]:.2e} km^2/s^3")
    rows["sizes"] = dict(measured=f"{N_H0} / {N_H1} / {N_TEST}", note="input, as in the paper: per policy on the 9:2 and the "
                      "inner-band stable NRHO, at both tunings; the outer-band stable NRHO (our added candidate) runs "
                      "reduced sizes, " + " / ".join(str(n) for n in counts["outer_sizes"]))
    c_inc = [100 * x for h in ("H0", "H1") for x in spike["constant", h]["inc"]]
    fig10_lim = spike_limit
    fig10_why = [f"{h} {w} {100 * x:.1f} % inconsistent" for h in ("H0", "H1")
                 for w, x in zip(("forward", "smoothed"), spike["constant", h]["inc"]) if x > fig10_lim]
    if spike["constant", "H1"]["sig_km"] <= spike["apoapsis window", "H1"]["sig_km"]:
        fig10_why.append("bound not larger than the window tuning's")
    rows["fig10"] = dict(measured=bool(fig10_ok), shown=f"inconsistent runs H0 fwd/smo {c_inc[0]:.1f}/{c_inc[1]:.1f} %, H1 "
                      f"{c_inc[2]:.1f}/{c_inc[3]:.1f} %; mean forward 3-sigma {spike['constant', 'H1']['sig_km']:.2f} km vs "
                      f"{spike['apoapsis window', 'H1']['sig_km']:.2f} km (window)",
                      note=f"{N_SPIKE} + {N_SPIKE} quiet runs at f = 0.1; limit {100 * fig10_lim:.0f} % per cell "
                      "(until 2026-11-26 widened by two binomial standard errors, 14.2 % for 200 runs, after 10.5 % had "
                      "been seen)", reason="; ".join(fig10_why))
    rows["fig11"] = dict(measured=min(fig11_h1, fig11_h0), shown=f"H1 runs with smoothed contrast >= 2 and above the forward "
                      f"one: {100 * fig11_h1:.0f} %; H0 runs without a smoothed spike: {100 * fig11_h0:.0f} %",
                      note="contrast = mean control norm within 6 h of the burn over the mean elsewhere",
                      reason=f"no distinct smoothed spike in {100 * (1 - fig11_h1):.0f} % of the burn runs"
                      if fig11_h1 < 0.9 else "the smoothed control also spikes without a burn")
    zr = studies["9:2 NRHO", "quiet"].h1.z / studies["9:2 NRHO", "quiet"].h1.z_step
    zr_c = studies_c["9:2 NRHO", "quiet"].h1.z / studies_c["9:2 NRHO", "quiet"].h1.z_step
    z0 = studies["9:2 NRHO", "quiet"].h0.z / studies["9:2 NRHO", "quiet"].h0.z_step  # the same test without a burn
    z0_c = studies_c["9:2 NRHO", "quiet"].h0.z / studies_c["9:2 NRHO", "quiet"].h0.z_step
    spike = min(np.mean(zr > 2), np.mean(zr_c > 2))
    quiet = min(np.mean(z0 <= 2), np.mean(z0_c <= 2))
    rows["fig13"] = dict(measured=float(min(spike, quiet)),
                      shown=f"quiet H1 runs with smoothed z above twice the forward z: {100 * np.mean(zr > 2):.1f} % (f = 0.1), "
                      f"{100 * np.mean(zr_c > 2):.1f} % (f_c); H0 runs without such a spike: {100 * np.mean(z0 <= 2):.1f} % "
                      f"/ {100 * np.mean(z0_c <= 2):.1f} %; median ratio H1 {np.median(zr):.0f} / {np.median(zr_c):.0f}, "
                      f"H0 {np.median(z0):.0f} / {np.median(z0_c):.0f}",
                      note="9:2 NRHO training runs; the forward control does rise inside the window (it scales with q_w), by "
                      "the median ratios given it stays well below the smoothed one",
                      reason=(f"the window raises the smoothed control without a burn too: {100 * (1 - quiet):.0f} % of the "
                              "no-burn runs show the same spike, so the spike alone does not indicate a maneuver (the "
                              "detection rows, Tables 5-8, judge z against its threshold)") if quiet < 0.9 else
                      f"no distinct smoothed spike in {100 * (1 - spike):.0f} % of the burn runs")
    edge = {v: tmap.edge(v) for v in VARIANTS}
    worst_c = max(max(v["c"]) for v in nees_rows.values())
    rows["window consistent"] = dict(
        measured=worst_c, shown=f"every orbit, policy and hypothesis at most 10 % inconsistent runs for f >= {F_C:g} (map); "
        f"at f_c the paper-size runs' worst cell is {100 * worst_c:.1f} %", note="smallest consistent f on the 9:2 NRHO by "
        "setting: " + ", ".join(f"{v} {edge[v] if edge[v] is not None else '> ' + str(F_SIDE[-1])}" for v in VARIANTS))
    for o in ORBITS:
        wf = max(nees_rows[o, p, h]["tune"][0] for p in POLICIES for h in ("H0", "H1"))
        ws = max(nees_rows[o, p, h]["tune"][1] for p in POLICIES for h in ("H0", "H1"))
        bad = [f"{p} {h}" for p in POLICIES for h in ("H0", "H1") if max(nees_rows[o, p, h]["tune"]) > 0.10]
        rows[f"window consistent f=0.1, {o}"] = dict(
            measured=max(wf, ws), shown=f"worst cell: {100 * wf:.1f} % / {100 * ws:.1f} % of runs inconsistent"
            + (f"; cells above 10 %: {', '.join(bad)}" if bad else ""),
            note=f"all training runs (up to {N_H0} H0 + {N_H1} H1 per policy)")
    for p in POLICIES:
        paper, zl = PAPER_ZLIM[p], studies["9:2 NRHO", p].threshold.z_lim
        rows[f"z_lim f=0.1, {p}"] = dict(measured=zl, shown=f"{zl * 1e3:.2f} mm/s", note=f"{100 * (zl / paper - 1):+.0f} %; the "
                                      f"map's z_lim equals the paper's at f = {F_MATCH[p]:.2f}")
        zc, sc_ = studies_c["9:2 NRHO", p].threshold.z_lim, se(("9:2 NRHO", p), "f_c", 0)
        n0, n1 = len(studies_c["9:2 NRHO", p].h0), len(studies_c["9:2 NRHO", p].h1)
        sp_ = paper_threshold_standard_error(sc_, zc, paper, n0, n1)
        sd_ = threshold_comparison_standard_error(sc_, zc, paper, n0, n1)
        tol_z = CLAIMS[f"z_lim f_c, {p}"].criterion.half_width(sd_)
        rows[f"z_lim f_c, {p}"] = dict(
            measured=zc, standard_error=sd_, shown=f"{zc * 1e3:.2f} +- {sc_ * 1e3:.2f} mm/s",
            reason=f"{100 * (zc / paper - 1):+.0f} %, {(zc - paper) / sd_:+.1f} standard errors of the difference "
            f"({abs(zc - paper) * 1e3:.2f} mm/s against a tolerance of {tol_z * 1e3:.2f} mm/s)",
            note=f"standard errors: ours {sc_ * 1e3:.2f} mm/s (bootstrap, {n0} + {n1} runs), the paper's "
            f"{sp_ * 1e3:.2f} mm/s (our relative error at its value, its {PAPER_TRAINING_RUNS[0]} + "
            f"{PAPER_TRAINING_RUNS[1]} runs), combined {sd_ * 1e3:.2f} mm/s; f_c = {F_C:g}; the map's z_lim equals the "
            f"paper's at f = {F_MATCH[p]:.2f}, "
            + ("below f_c, where our filter is not consistent with a burn" if F_MATCH[p] < F_C else "inside the consistent range"))
    if joint is not None:
        passed, b8 = joint.passed, joint.best_8h()
        rows["joint 8h"] = dict(
            measured=joint.any_8h,
            shown=f"{len(joint.screen)} settings screened ({joint.n_screen[0]} + {joint.n_screen[1]} runs per policy), "
            f"{len(joint.confirm)} rerun at {joint.n_paper[0]} + {joint.n_paper[1]}; both criteria met at windows "
            f"{', '.join(f'{w:g} h' for w in joint.windows_passed()) or 'none'}",
            note=(f"closest 8-h setting of the screen: {joint.label(b8[0])}, worst cell {100 * b8[1]:.0f} %, z_lim "
                  f"{100 * b8[2]:.0f} % off" if b8 is not None else "no 8-h setting screened"),
            reason="no 8-h setting meets both at paper size" + ("" if passed else "; no confirmed setting does "
                                                                 "(windows confirmed: " + (", ".join(
                f"{w:g} h" for w in sorted({k[0] for k in joint.confirm})) or "none") + ")"))
        rows["joint windows"] = dict(
            measured="; ".join(f"{joint.label(k)}: " + ", ".join(
                f"{p} {joint.confirm[k][p]['z_lim'] * 1e3:.2f} +- {joint.confirm[k][p]['z_lim_se'] * 1e3:.2f} mm/s"
                for p in joint.policies) for k in passed[:4]) + (f" (and {len(passed) - 4} more)" if len(passed) > 4 else "")
            or "none", note=f"screen passed by {len(joint.screen_passed)} of {len(joint.screen)} settings; rerun at paper size: "
            f"{len(joint.confirm)} (windows {', '.join(f'{w:g} h' for w in sorted({k[0] for k in joint.confirm})) or 'none'}); "
            f"bootstrap standard errors over {joint.n_boot} resamples; paper {PAPER_ZLIM['active'] * 1e3:.1f} / "
            f"{PAPER_ZLIM['quiet'] * 1e3:.2f} mm/s")
    for o in STABLE:
        for p in POLICIES:
            rows[f"z_lim, {o}, {p}"] = dict(measured=f"{studies[o, p].threshold.z_lim * 1e3:.2f} mm/s (f = 0.1), "
                                         f"{studies_c[o, p].threshold.z_lim * 1e3:.2f} mm/s (f_c)")
    for (o, p), st in studies_c.items():
        rows[f"FP/MD, {o}, {p}"] = dict(
            measured=f"{st.threshold.false_positive:.4f} / {st.threshold.missed_detection:.4f} (f = 0.1: "
            f"{studies[o, p].threshold.false_positive:.4f} / {studies[o, p].threshold.missed_detection:.4f})",
            note=f"{st.threshold.crossings.size} PDF crossing(s); FP + MD standard error {se((o, p), 'f_c', 1):.4f} (bootstrap)")
    n_cross = [st.threshold.crossings.size for g in (studies, studies_c) for st in g.values()]
    rows["one crossing"] = dict(measured=all(c == 1 for c in n_cross), shown=f"crossings per case (both tunings): {n_cross}",
                             note="z_lim is the crossing of least total error")
    for p in POLICIES:
        n, paper = studies["9:2 NRHO", p].score.n, PAPER_ACCURACY[p]
        for tag, a in (("f=0.1", acc[("9:2 NRHO", p), "f = 0.1"]), ("f_c", acc[("9:2 NRHO", p), "f_c"])):
            se_a = accuracy_comparison_standard_error(paper, n)
            tol_a = ACCURACY_DIGIT_TOL + 2 * se_a
            rows[f"accuracy {tag}, {p}"] = dict(measured=a, shown=f"{100 * a:.1f} %", standard_error=se_a,
                                             note=f"{n} test runs; " + accuracy_exact_text(a, paper, n),
                                             reason=f"{100 * (a - paper):+.1f} points, {100 * (abs(a - paper) - tol_a):.1f} "
                                             f"points beyond the {100 * tol_a:.1f}-point tolerance (half a printed point "
                                             f"+ 2 x {100 * se_a:.2f}, ours and the paper's binomial errors combined)")
    for o in STABLE:
        for p in POLICIES:
            e_s, e_n = studies_c[o, p].threshold.total_error, studies_c["9:2 NRHO", p].threshold.total_error
            se_s, se_n = se((o, p), "f_c", 1), se(("9:2 NRHO", p), "f_c", 1)
            a_s, n_s = acc[(o, p), "f_c"], studies_c[o, p].score.n
            a_n = acc[("9:2 NRHO", p), "f_c"]
            tol = ACCURACY_DIGIT_TOL + 2 * accuracy_standard_error(1.0, n_s)
            gain, s_d = e_n - e_s, float(np.hypot(se_s, se_n))
            z_d = improvement_in_standard_errors(e_s, e_n, se_s, se_n)
            n_o = counts["outer_sizes"] if o == ORBITS[2] else (N_H0, N_H1, N_TEST)
            rows[f"stable better, {o}, {p}"] = dict(
                measured=float(gain), standard_error=s_d,
                shown=f"expected FP + MD {e_s:.4f} vs 9:2 {e_n:.4f}: stable lower by {gain:+.4f} +- {s_d:.4f} "
                f"({z_d:+.1f} standard errors, {'resolved' if abs(z_d) > 2 else 'not resolved'}); test accuracy "
                f"{100 * a_s:.1f} % vs {100 * a_n:.1f} % of {n_s}",
                note=f"cannot be tested at these sizes: the sign of a difference below {2 * s_d:.4f} in FP + MD "
                f"({100 * s_d:.2f} accuracy points), so 'better' itself is not confirmed; "
                f"{n_o[0]} + {n_o[1]} training runs and {n_o[2]} + {n_o[2]} tests per policy"
                + (" (reduced Monte Carlo)" if o == ORBITS[2] else "")
                + ("" if p == "active" else f"; accuracy vs the paper's 200/200: {100 * a_s:.1f} % "
                   f"({'within' if 1.0 - a_s <= tol + 1e-9 else 'outside'} {100 * tol:.1f} points)"),
                reason=(f"the 9:2 NRHO is resolved better ({z_d:+.1f} standard errors)" if gain < -2 * s_d else
                        f"the stable NRHO is better by more than marginally (more than {STABLE_MARGIN:g} in FP + MD, "
                        "the paper's 3-point gap)"))
    for p in POLICIES:
        (sl, cr, _, _), (sl1, cr1, _, _) = lin["9:2 NRHO", p, "f_c"], lin["9:2 NRHO", p, "f = 0.1"]
        rows[f"linear, {p}"] = dict(measured=float(cr), shown=f"f_c: slope {sl:.2f}, corr {cr:.3f} (f = 0.1: {sl1:.2f}, {cr1:.3f})")
    rows["gaussian"] = dict(measured=float(lin["9:2 NRHO", "active", "f_c"][3]),
                         shown=f"skewness {lin['9:2 NRHO', 'active', 'f_c'][3]:.2f} (f = 0.1: {lin['9:2 NRHO', 'active', 'f = 0.1'][3]:.2f})")
    ctr = {(p, t): lin["9:2 NRHO", p, t][2] for p in POLICIES for t in ("f = 0.1", "f_c")}
    c10 = pm_j.contrasts_at(10.0)
    rows["+-j"] = dict(measured=finite_or(ctr["active", "f_c"], 1.0),
                    shown=f"z/|dv| at +-90 deg over 0/180 deg: {ratio_text(ctr['active', 'f_c'])} (f_c), "
                    f"{ratio_text(ctr['active', 'f = 0.1'])} (f = 0.1)", reason=f"no +-j preference at our noise (paired 1 m/s "
                    f"burns: contrast {min(c10):.2f}-{max(c10):.2f} over f and burn time)")
    pm_a, pm_q = det.azimuth_contrast(pm_mc["active"]), det.azimuth_contrast(pm_mc["quiet"])
    ratio_a, ratio_q = (float(np.mean(pm_mc[p].z / pm_mc[p].magnitude)) for p in ("active", "quiet"))
    corr_a = float(np.corrcoef(pm_mc["active"].magnitude, pm_mc["active"].z)[0, 1])
    burn_time_effect = pm_j.burn_time_effect()
    rows["+-j conditions"] = dict(
        measured=f"largest paired contrast {pm_j.best[1]:.2f} at f = {f_pm:g}, {sig_pm:g} micro-rad (burn at apoapsis; a burn "
        f"3 h before or after apoapsis moves it by at most {burn_time_effect:.2f}); there the Fig. 16 statistic is "
        f"{ratio_text(pm_a)} (active), but z/|dv| averages {ratio_a:.2f} and corr(z, |dv|) is {corr_a:.2f}",
        note=f"{PM_J_SEEDS} noise draws per direction; {N_PM_J_MC} random burns per policy in that regime; the pattern needs "
        "burns that the angles see poorly (noise far above ours): then z falls short of the burn, least along +-j, "
        "perpendicular to the line of sight")
    rows["quiet uniform"] = dict(
        measured=bool(pm_a > 1.1 and pm_q < pm_a and ratio_q > 0.5),
        shown=f"where the pattern appears ({sig_pm:g} micro-rad, f = {f_pm:g}): quiet {ratio_text(pm_q)} vs active "
        f"{ratio_text(pm_a)}; at our noise {ratio_text(ctr['quiet', 'f_c'])} vs {ratio_text(ctr['active', 'f_c'])}",
        reason="no +-j pattern to weaken in any regime searched" if not pm_a > 1.1 else "the quiet policy shows the "
        "pattern as much" if not pm_q < pm_a else f"there quiet burns are lost in the noise (mean z/|dv| {ratio_q:.2f}), "
        "so the quiet detection of Table 7 fails")
    for tag, f_ in (("f = 0.1", F_TUNE), ("f_c", F_C)):
        m, s1 = z05[f_].mean(), z05[f_].std(ddof=1)
        rows[f"health z, {tag}"] = dict(
            measured=float(m), standard_error=one_run_comparison_standard_error(s1, z05[f_].size),
            shown=f"{m:.4f} +- {s1:.4f} m/s (mean +- single-run sd, {N_Z05} runs)",
            note=f"z depends on f: {z05[F_GRID[0]].mean():.3f} m/s at f = {F_GRID[0]:g} to {z05[F_GRID[-1]].mean():.3f} at "
            f"f = {F_GRID[-1]:g}", reason=f"{(0.4761 - m) / s1:+.1f} single-run sd from our mean")
        rows[f"health sigma, {tag}"] = dict(measured=float(sig_level[tag]), shown=f"{sig_level[tag]:.1f} sigma",
                                         note="mean z of the 0.5 m/s burns against the quiet H1 training runs at the same tuning")
    for tag, h in lead.items():
        fr, i5 = h.outcome_fractions(), int(np.argmin(np.abs(h.magnitudes_m_s - 0.5)))
        holds = [f"{m:g}" for m, c in zip(h.magnitudes_m_s, fr["control first"]) if c > 0.5]
        rows["control first, " + tag.replace(f"f_c = {F_C:g}", "f_c")] = dict(
            measured=bool(fr["control first"][i5] > 0.5),
            shown="0.5 m/s: control first {:.0f} %, same epoch {:.0f} %, residual first {:.0f} %; control first at {}".format(
                100 * fr["control first"][i5], 100 * fr["same epoch"][i5], 100 * fr["residual first"][i5],
                ", ".join(f"{m:g} m/s {100 * c:.0f} %" for m, c in zip(h.magnitudes_m_s, fr["control first"]))),
            note=f"{N_LEAD[1]} burns per size; both tests online at a per-epoch tail of 0.135 %; false alarms over 24 h control "
            f"{100 * h.false_alarm_control:.1f} %, residual {100 * h.false_alarm_residual:.1f} %"
            + ("; noise ten times ours: a regime searched for the claim" if "100" in tag else ""),
            reason="at 0.5 m/s the control test is not first in most runs; "
            + (f"it is for {', '.join(holds)} m/s burns" if holds else "nor for any burn size raced")
            + (f"; the quiet window absorbs a median {np.median(h.z_final_m_s[i5]):.2f} m/s of the 0.5 m/s burn"
               if "100" in tag else ""))
    if lead_grid is not None:
        hold = lead_grid.holding
        best = max(lead_grid.cells, key=lambda k: lead_grid.summary(k)["residual_silent"])
        sb = lead_grid.summary(best)
        rows["race grid"] = dict(
            measured=bool(hold),
            shown=f"{len(lead_grid.cells)} {'cells' if len(lead_grid.cells) > 1 else 'cell'} "
            f"(f {', '.join(sorted({f'{k[0]:g}' for k in lead_grid.cells}))}; noise "
            f"{', '.join(sorted({f'{k[1]:g}' for k in lead_grid.cells}, key=float))} micro-rad); the combination holds in "
            + (", ".join(f"f = {f:g} / {s_:g} urad" for f, s_ in hold) or "none"),
            note=f"most benign residuals at f = {best[0]:g}, {best[1]:g} micro-rad: residual test silent in "
            f"{100 * sb['residual_silent']:.0f} % of {lead_grid.magnitude_m_s:g} m/s runs, control first in "
            f"{100 * sb['control_first']:.0f} %, median z/burn {sb['z_ratio']:.2f}")
    if health_runs is not None:
        pool = HealthRuns.pooled(health_runs.values())
        i5s = {t: int(np.argmin(np.abs(h.magnitudes_m_s - 0.5))) for t, h in lead.items()}
        race_silent = "; ".join(f"{t.replace(f'f_c = {F_C:g}', 'f_c')} {100 * (h.residual_epoch[i5s[t]] < 0).mean():.0f} %"
                                for t, h in lead.items())
        l100 = lead.get("f = 0.1, 100 urad")
        edge_h = HEALTH_PLAUSIBLE_FLOOR - 2 * pool.floor_standard_error
        rows["residuals benign"] = dict(
            measured=pool.share, standard_error=pool.floor_standard_error,
            shown=f"{100 * pool.share:.1f} % of {len(pool)} runs at 10 micro-rad ("
            + ", ".join(f"{t}: {int(r.benign_while_diverging.sum())}/{len(r)}" for t, r in health_runs.items())
            + f"); the figure's single run: smoothed NEES mean {health_nees_mean:.0f}, whole-track residual median "
            f"{np.median(health_residual_norms):.2f}",
            note=f"the 0.5 m/s burns of Section 6 refiltered; pooled: {pool.text()}; the race's own 0.5 m/s runs with "
            f"a silent residual test: {race_silent}"
            + (f" (at 100 micro-rad the control test is silent too in "
               f"{100 * l100.outcome_fractions()['neither'][i5s['f = 0.1, 100 urad']]:.0f} %)" if l100 is not None
               else ""),
            reason=f"the paper's run is not a plausible draw at our noise: {int(pool.benign_while_diverging.sum())} of "
            f"{len(pool)} runs show the combination, below the floor ({100 * edge_h:.1f} %); the estimate diverges in "
            f"{100 * pool.diverged.mean():.0f} % of the runs but the residual test fires within 24 h of the burn in "
            f"{100 * (1 - pool.residual_silent.mean()):.0f} %; of the noise levels raced, the residuals look benign only "
            f"at {100e-6 / sigma_angle_rad:g} times our angle noise, and then z misses the burn as well (Section 6)")
    return rows

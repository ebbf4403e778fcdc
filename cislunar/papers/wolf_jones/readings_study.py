"""Wolf & Jones test cases 1 and 2 under every reading of the process noise of Tables 3 and 5 (issue 22, item 3).

Tables 3 and 5 print "Q [km/s^3] = 1e-11"; :data:`cislunar.papers.wolf_jones.scenarios.PROCESS_NOISE_READINGS_KM2_S3`
lists the four readings (the literal 1e-11 km^2/s^3 and three small ones, among them the adopted 1e-11 LU^2/TU^3).
For the plans a notebook already has (planned under the adopted reading: notebooks 05 and 06 plan once and do not
re-plan per reading), :func:`evaluate_readings` recomputes under each reading the CRLB of the paper's "Performance
Evaluation" (process noise along each plan) and the window MI (Eq. 18, same Q), and tests the two conclusions of
Figs. 9 and 10 that notebook 06 judges, "alpha_h = 0 weakly observable" and "MI correlates with estimator
performance", with the criteria fixed in :mod:`cislunar.papers.wolf_jones.claims.process_noise_readings`.

Why the plans are not re-solved per reading: the notebooks' question is whether the statuses of their rows depend
on the unstated unit, for the trajectories they show; re-planning would ask a different question (what the paper's
method plans under another reading) at four times the cost of the sweep.  The MI judged under a reading is the MI
under that reading along each plan (the paper computes MI and CRLB with one Q); the MI the planner maximised (Q of
the adopted reading, held along the ballistic arc) is kept beside it (``mi_planned``) and its correlations are
reported too.

Units: RMS in km, MI in nats, impulse in m/s, times in TU unless a name says ``days``; states are rotating-frame
barycentric CR3BP states in LU and LU/TU.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import spearmanr

from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.papers.wolf_jones import test_case_studies as studies
from cislunar.papers.wolf_jones.case_2_closing import Measurement
from cislunar.papers.wolf_jones.claims.process_noise_readings import CORR_LIMIT, WEAK_FACTOR
from cislunar.sensing import covariance as cov
from cislunar.utils import validation

__all__ = ["ReadingRow", "ReadingsStudy", "evaluate_readings", "case2_readings", "case1_readings"]

#: Short names of the four readings, in the order of ``PROCESS_NOISE_READINGS_KM2_S3``.
_SHORT = {1e-11: "1e-11 km^2/s^3 (literal)", 1e-17: "1e-11 m^2/s^3", 1e-22: "(1e-11)^2 km^2/s^3"}


def _short(label: str, q_km: float) -> str:
    if "adopted" in label:
        return "1e-11 LU^2/TU^3 (adopted)"
    return _SHORT.get(q_km, label)


def _rank(a, b) -> float:
    """Spearman rank correlation (nan for fewer than three points or a constant input)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.size < 3 or np.ptp(a) == 0 or np.ptp(b) == 0:
        return float("nan")
    return float(spearmanr(a, b).statistic)


@dataclass(frozen=True)
class ReadingRow:
    """The plans of one sweep evaluated under one reading of the process noise.

    Attributes
    ----------
    label : str
        The reading (key of ``PROCESS_NOISE_READINGS_KM2_S3``).
    q_km2_s3 : float
        Acceleration PSD, km^2/s^3.
    t : ndarray (N,)
        Measurement times of the window, TU.
    rms_km : ndarray (n_plans, n_objects, N)
        Position RMS (CRLB) of the observer (object 0) and each target over the window, km.
    mi : ndarray (n_plans,)
        Window MI (Eq. 18) under this reading, process noise along each plan, nats.
    """

    label: str
    q_km2_s3: float
    t: np.ndarray
    rms_km: np.ndarray
    mi: np.ndarray

    @property
    def name(self) -> str:
        """A short name of the reading."""
        return _short(self.label, self.q_km2_s3)

    @property
    def adopted(self) -> bool:
        return "adopted" in self.label

    @property
    def terminal_obs_km(self) -> np.ndarray:
        """Observer position RMS after the last measurement, per plan, km."""
        return self.rms_km[:, 0, -1]

    @property
    def terminal_tgt_km(self) -> np.ndarray:
        """Targets' mean position RMS after the last measurement, per plan, km."""
        return self.rms_km[:, 1:, -1].mean(axis=1)

    @property
    def mean_obs_km(self) -> np.ndarray:
        """Observer position RMS averaged over the window's measurement times, per plan, km."""
        return self.rms_km[:, 0].mean(axis=1)

    @property
    def mean_tgt_km(self) -> np.ndarray:
        """Targets' position RMS averaged over the window and the targets, per plan, km."""
        return self.rms_km[:, 1:].mean(axis=(1, 2))


@dataclass(frozen=True)
class ReadingsStudy:
    """One sweep's plans under every reading of the process noise (:func:`evaluate_readings`).

    Attributes
    ----------
    case : int
        Test case (1 or 2).
    alphas : tuple of float
        Homotopy weight of each plan, increasing.
    dv_mps : ndarray
        Total impulse of each plan, m/s (nan if not given).
    mi_planned : ndarray
        The MI each plan was planned with (adopted reading, Q held along the ballistic arc), nats (nan if not given).
    rows : tuple of ReadingRow
        One per reading, in the order of ``PROCESS_NOISE_READINGS_KM2_S3``.
    """

    case: int
    alphas: tuple
    dv_mps: np.ndarray
    mi_planned: np.ndarray
    rows: tuple

    # --- Fig. 9: weakly observable -------------------------------------------------------------------------------
    def _weak(self, values) -> float:
        a = np.asarray(self.alphas)
        if not np.any(a == 0.0) or not np.any(a > 0.0):
            return float("nan")
        return float(values[a == 0.0][0] / np.max(values[a > 0.0]))

    def weak_ratio(self, row: ReadingRow) -> float:
        """alpha_h = 0 terminal observer RMS over the largest of the alpha_h > 0 plans (nan without both)."""
        return self._weak(row.terminal_obs_km)

    def weak_ratio_mean(self, row: ReadingRow) -> float:
        """The same with the window-mean observer RMS."""
        return self._weak(row.mean_obs_km)

    # --- Fig. 10: MI against the CRLB ----------------------------------------------------------------------------
    def ranks(self, row: ReadingRow, planned: bool = False) -> tuple:
        """Spearman(MI, terminal RMS) of the observer and of the targets' mean; MI under ``row``'s reading, or the
        planning MI when ``planned``."""
        mi = self.mi_planned if planned else row.mi
        return _rank(mi, row.terminal_obs_km), _rank(mi, row.terminal_tgt_km)

    def corr(self, row: ReadingRow, planned: bool = False) -> float:
        """The larger (worse) of the two :meth:`ranks`."""
        return float(max(self.ranks(row, planned)))

    # --- verdicts per reading ------------------------------------------------------------------------------------
    def weak_holds(self, row: ReadingRow) -> bool:
        return bool(self.weak_ratio(row) >= WEAK_FACTOR)

    def corr_holds(self, row: ReadingRow) -> bool:
        return bool(self.corr(row) <= CORR_LIMIT)

    @property
    def adopted(self) -> ReadingRow:
        return next(r for r in self.rows if r.adopted)

    def conclusions(self) -> dict:
        """``name -> readings (short names) under which the conclusion fails`` for the conclusions this study can
        test ("weakly_observable": test case 2 with alpha_h = 0 and alpha_h > 0 plans; "mi_correlation": three
        plans or more); an empty list means it holds under every reading."""
        out = {}
        if self.case == 2 and np.isfinite(self.weak_ratio(self.rows[0])):
            out["weakly_observable"] = [r.name for r in self.rows if not self.weak_holds(r)]
        if len(self.alphas) >= 3:
            out["mi_correlation"] = [r.name for r in self.rows if not self.corr_holds(r)]
        return out

    @property
    def spread(self) -> float:
        """Largest over smallest terminal observer RMS across the three small readings, worst plan."""
        small = np.array([r.terminal_obs_km for r in self.rows if r.q_km2_s3 < 1e-12])
        return float(np.max(small.max(axis=0) / small.min(axis=0)))

    def _measurement(self, key: str, values: list, holds: list, worst, shown: str) -> tuple:
        """``(Measurement, claim key)`` by the rule of the claims module: the ``_every`` row on the worst value if it holds under every reading,
        else the tuned ``_adopted`` row on the adopted reading's value, its note naming the failing readings."""
        fails = [r.name for r, h in zip(self.rows, holds) if not h]
        if not fails:
            return Measurement(worst, shown=shown, note="holds under all four readings"), f"{key}_every"
        i = next(n for n, r in enumerate(self.rows) if r.adopted)
        return (Measurement(values[i], shown=shown, note="fails under " + ", ".join(fails)),
                f"{key}_adopted")

    def measurements(self) -> dict:
        """``claim key -> Measurement`` of the rows this study judges (keys of
        :data:`cislunar.papers.wolf_jones.claims.process_noise_readings.CLAIMS`; the key already follows the rule
        of that module: ``*_every`` when the conclusion holds under every reading, else ``*_adopted``)."""
        out = {}
        prefix = f"case{self.case}"
        if self.case == 2 and np.isfinite(self.weak_ratio(self.rows[0])):
            vals = [self.weak_ratio(r) for r in self.rows]
            m, key = self._measurement(f"{prefix}_weakly_observable", vals, [self.weak_holds(r) for r in self.rows],
                                       min(vals), "alpha_h = 0 RMS / worst alpha_h > 0 RMS: " + "; ".join(
                                           f"{r.name} {v:.2f}" for r, v in zip(self.rows, vals)))
            mean = ", ".join(f"{self.weak_ratio_mean(r):.2f}" for r in self.rows)
            out[key] = Measurement(m.value, shown=m.shown, note=m.note + f"; window-mean RMS ratios {mean} (same order)")
        if len(self.alphas) >= 3:
            vals = [self.corr(r) for r in self.rows]
            planned = [self.corr(r, planned=True) for r in self.rows] if np.all(np.isfinite(self.mi_planned)) else []
            m, key = self._measurement(
                f"{prefix}_mi_correlation", vals, [self.corr_holds(r) for r in self.rows], max(vals),
                "Spearman(MI, RMS) (worse of observer, targets): " + "; ".join(
                    f"{r.name} {v:+.2f}" for r, v in zip(self.rows, vals))
                + (" (with the planning MI: " + ", ".join(f"{v:+.2f}" for v in planned) + ")" if planned else ""))
            out[key] = m
        return out

    def summary(self) -> str:
        """A table per reading: terminal and window-mean RMS per plan, the two verdicts."""
        lines = [f"test case {self.case}: {len(self.alphas)} plans (alpha_h "
                 + ", ".join(f"{a:g}" for a in self.alphas) + ") under each reading of Q"]
        for r in self.rows:
            ro, rt = self.ranks(r)
            po, pt = self.ranks(r, planned=True)
            lines.append(f"  {r.name:<28} q = {r.q_km2_s3:.2e} km^2/s^3")
            lines.append("    terminal observer RMS [km]: " + ", ".join(f"{v:.1f}" for v in r.terminal_obs_km)
                         + "; window mean: " + ", ".join(f"{v:.1f}" for v in r.mean_obs_km))
            lines.append("    MI [nats]: " + ", ".join(f"{v:.2f}" for v in r.mi))
            wr = self.weak_ratio(r)
            if np.isfinite(wr):
                lines.append(f"    alpha_h = 0 / worst alpha_h > 0: terminal {wr:.2f}x, window mean "
                             f"{self.weak_ratio_mean(r):.2f}x" + (f" -> weakly observable (>= {WEAK_FACTOR:g}x): "
                                                                  f"{self.weak_holds(r)}" if self.case == 2 else ""))
            lines.append(f"    Spearman(MI, RMS): observer {ro:+.2f}, targets {rt:+.2f} (planning MI: {po:+.2f}, "
                         f"{pt:+.2f}) -> correlates well (<= {CORR_LIMIT:g}): {self.corr_holds(r)}")
        lines.append(f"terminal RMS spread over the three small readings (worst plan): {self.spread:.2f}x")
        for name, fails in self.conclusions().items():
            lines.append(f"{name}: " + ("holds under every reading" if not fails else "fails under " + ", ".join(fails)))
        return "\n".join(lines)


def evaluate_readings(scenario: wj.Scenario, alphas, x_window_starts, *, dv_mps=None, mi_planned=None,
                      readings: dict | None = None) -> ReadingsStudy:
    """Evaluate fixed plans under every reading of the process noise.

    Parameters
    ----------
    scenario : Scenario
        Test case 1 or 2 (its own ``q`` is not used).
    alphas : sequence of float
        Homotopy weight of each plan, strictly increasing, in [0, 1].
    x_window_starts : array_like (n_plans, 6)
        Observer state of each plan at the window start, rotating frame, LU and LU/TU.
    dv_mps, mi_planned : array_like (n_plans,), optional
        Total impulse (m/s) and planning MI (nats) of each plan, carried along for the figure and the report.
    readings : dict, optional
        ``label -> PSD in km^2/s^3`` (default: ``PROCESS_NOISE_READINGS_KM2_S3``); one label must contain
        "adopted".

    Returns
    -------
    ReadingsStudy
    """
    validation.instance(scenario, "scenario", wj.Scenario)
    alphas = validation.as_array(alphas, "alphas", ndim=(1,))
    if alphas.size == 0 or np.any(np.diff(alphas) <= 0) or alphas[0] < 0 or alphas[-1] > 1:
        raise ValueError(f"alphas must be strictly increasing in [0, 1]; got {alphas}")
    x = validation.as_array(x_window_starts, "x_window_starts", shape=(alphas.size, 6))
    n = alphas.size
    extra = []
    for value, name in ((dv_mps, "dv_mps"), (mi_planned, "mi_planned")):
        extra.append(np.full(n, np.nan) if value is None else
                     validation.as_array(value, name, shape=(n,)))
    readings = wj.PROCESS_NOISE_READINGS_KM2_S3 if readings is None else validation.instance(
        readings, "readings", dict, "a dict {label: PSD km^2/s^3}")
    if not readings or sum("adopted" in k for k in readings) != 1:
        raise ValueError(f"readings must hold exactly one label containing 'adopted'; got {list(readings)}")
    rows = []
    for label, q_km in readings.items():
        q_nd = cov.psd_to_nondimensional(validation.positive(q_km, f"readings[{label!r}]"), scenario.system)
        crlbs = [wj.evaluate_crlb(scenario, xi, q=q_nd) for xi in x]
        rows.append(ReadingRow(str(label), float(q_km), crlbs[0].t, np.stack([c.rms_km for c in crlbs]),
                               np.array([c.mutual_information for c in crlbs])))
    return ReadingsStudy(scenario.number, tuple(float(a) for a in alphas), extra[0], extra[1], tuple(rows))


def case2_readings(case: studies.Case2Sweep) -> ReadingsStudy:
    """Notebook 06's converged plans (``case.ok``) under every reading."""
    validation.instance(case, "case", studies.Case2Sweep)
    ok = case.ok
    return evaluate_readings(case.scenario, [r.alpha for r in ok], [r.res.x[case.k_ws] for r in ok],
                             dv_mps=[r.dv for r in ok], mi_planned=[r.mi for r in ok])


def case1_readings(case: studies.Case1Sweep) -> ReadingsStudy:
    """Notebook 05's best plan per weight (``case.best``) under every reading."""
    validation.instance(case, "case", studies.Case1Sweep)
    return evaluate_readings(case.scenario, case.alphas, [r.x[case.k_ws] for r in case.best],
                             dv_mps=case.impulse_mps, mi_planned=case.mi)

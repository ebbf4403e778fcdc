r"""The DRO tables of Wolf & Jones (Tables 2 and 4) as studies that return frozen results (chapter 01).

Wolf & Jones print the initial states of their distant retrograde orbits (DROs) to nine digits but give no value
of the Earth-Moon mass ratio :math:`\mu`, of the length unit or of the time unit.  This module asks what the
printed rows tell us about those inputs:

* :func:`dro_table_study`: every printed row verified (:func:`cislunar.papers.wolf_jones.reference.verify_table_row`),
  the rows grouped into distinct orbits (Tables 2 and 4 print the same observer start), and a DRO family across
  the window the orbits occupy, for the chapter's figure;
* :func:`mu_closure_study`: the largest closure of the rows that are periodic as printed, for trial values of
  :math:`\mu`; the rows *pin* :math:`\mu` when they close within
  :data:`~cislunar.papers.wolf_jones.reference.CLOSURE_TOL` at the adopted value and fail for every trial at least
  ``0.9e-9`` away;
* :func:`window_study`: the day counts the text gives for the observation windows of the two test cases
  (:math:`[3P/4, 3P/2]`, "between 12 and 23 days"; :math:`[P, 2P]`, "between roughly 17 and 32 days") against the
  two readings of the time unit, the standard :math:`\sqrt{L^3/G(M_E+M_M)}` and the literal
  :math:`P_{synodic}/2\pi`.

Units: states non-dimensional (rotating frame, LU and LU/TU), crossings in km from the Moon's centre, periods and
windows in days unless a name says ``_tu``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import CR3BP, SYNODIC_MONTH_DAYS, check_system
from cislunar.cr3bp.orbits import PeriodicOrbit
from cislunar.papers.wolf_jones import reference
from cislunar.utils import validation

__all__ = [
    "DroGroup",
    "DroTableStudy",
    "MuClosureStudy",
    "PUBLISHED_MU",
    "PAPER_WINDOWS_DAYS",
    "TABLE_ROWS",
    "WINDOW_TOL_DAYS",
    "WindowStudy",
    "dro_table_study",
    "mu_closure_study",
    "mu_trials",
    "row_label",
    "window_study",
]

#: Rows of Tables 2 and 4 as the chapter labels them (Table 4's labels other than target3_t0 are inferred).
TABLE_ROWS = ((2, "observer_t0"), (2, "observer_tf"), (2, "target1_t0"), (4, "observer_t0"), (4, "observer_tf"),
              (4, "target1_t0"), (4, "target2_t0"), (4, "target3_t0"))
#: Values of :math:`\mu` found in the literature and tried besides the adopted one and its neighbours.
PUBLISHED_MU = (0.0121505856, 0.01215058, 0.01215)
#: Day counts of the text: test case 1's window "between 12 and 23 days", test case 2's "between roughly 17 and 32".
PAPER_WINDOWS_DAYS = ((12.0, 23.0), (17.0, 32.0))
#: Fractions of the observer's DRO period that bound the two windows: [3P/4, 3P/2] and [P, 2P].
WINDOW_FRACTIONS = ((0.75, 1.5), (1.0, 2.0))
#: Tolerance on each window end, days (as in notebook 05).
WINDOW_TOL_DAYS = 1.0
#: Trials at least this far from the adopted :math:`\mu` must fail for the rows to pin it.
MU_PIN_OFFSET = 0.9e-9


def row_label(table: int, label: str) -> str:
    """Legend and table label of a printed row; Table 4's labels other than target3_t0 are lost in the paper's
    text (our inference)."""
    table = validation.choice(table, "table", (2, 4))
    validation.instance(label, "label", str)
    return f"Table {table}: {label}" + (" (label inferred)" if table == 4 and label != "target3_t0" else "")


# ---------------------------------------------------------------------------------------------------------------
# The printed rows, grouped into distinct orbits
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DroGroup:
    """One distinct printed orbit and every row that prints it.

    Attributes
    ----------
    checks : tuple of RowCheck
        The rows (same printed ``x0`` and ``vy0``).
    crossing_km : float
        Where the orbit crosses the x axis, km from the Moon's centre (negative: on the Earth side).
    """

    checks: tuple
    crossing_km: float

    @property
    def orbit(self) -> PeriodicOrbit:
        """The periodic orbit through the printed ``x0`` (corrected when the row is not periodic as printed)."""
        return self.checks[0].corrected

    @property
    def label(self) -> str:
        """The labels of every row that prints this orbit, joined by ``=``."""
        return " = ".join(row_label(c.table, c.label) for c in self.checks)


@dataclass(frozen=True)
class DroTableStudy:
    """Tables 2 and 4 verified, grouped and placed on the DRO family.

    Attributes
    ----------
    checks : tuple of RowCheck
        Every printed row, in file order.
    groups : tuple of DroGroup
        Distinct orbits, sorted by x-axis crossing (left to right in the chapter's zoom panel).
    family : tuple of PeriodicOrbit
        DRO family members from 0.95 LU to 0.70 LU (Earth side of the Moon).
    zoom_family : tuple of PeriodicOrbit
        Twelve members across the crossings of the printed orbits, 1500 km beyond each end.
    rounding : tuple of RoundingBound
        Per row (order of ``checks``), the closure that rounding the printed nine decimals can explain
        (:func:`cislunar.papers.wolf_jones.reference.rounding_bound`).
    """

    checks: tuple
    groups: tuple
    family: tuple
    zoom_family: tuple
    system: CR3BP
    rounding: tuple = ()

    @property
    def closure_ratios(self) -> tuple:
        """Per row, its closure as printed over the closure its rounding can explain (<= 1: a rounded periodic
        state)."""
        return tuple(float(c.raw_closure / b.closure) for c, b in zip(self.checks, self.rounding))

    @property
    def observer(self):
        """The observer's start row (the same in both tables; the first found)."""
        return next(c for c in self.checks if c.label == "observer_t0")

    @property
    def figure_groups(self) -> list:
        """``(orbit, label)`` per distinct orbit, as the DRO figure takes them."""
        return [(g.orbit, g.label) for g in self.groups]

    def jacobi_ranges(self) -> dict:
        """(min, max) Jacobi constant of the corrected targets and of every row but the observer's start."""
        targets = [c.corrected.jacobi for c in self.checks if c.label.startswith("target")]
        others = [c.corrected.jacobi for c in self.checks if c.label != "observer_t0"]
        return {"targets": (min(targets), max(targets)), "others": (min(others), max(others))}

    def rows_report(self) -> str:
        """One line per printed row: printed and corrected ``vy0``, closure as printed, period, Jacobi constant."""
        lines = [f"{'table':>5} {'row':>12} {'printed vy0':>12} {'corrected vy0':>14} {'closure as printed':>19} "
                 f"{'period [d]':>10} {'Jacobi C':>12}"]
        for c in self.checks:
            lines.append(f"{c.table:>5} {c.label:>12} {c.vy0:12.9f} {c.corrected.x0[4]:14.9f} {c.raw_closure:19.2e} "
                         f"{c.corrected.period_days:10.4f} {c.corrected.jacobi:12.9f}")
        return "\n".join(lines)

    def observer_report(self) -> str:
        """The observer's printed and corrected Jacobi constants against the other rows'."""
        obs, rng = self.observer, self.jacobi_ranges()
        printed = self.system.jacobi(np.array([obs.x0, 0, 0, 0, obs.vy0, 0]))
        return (f"printed observer state: C = {printed:.6f}; corrected: C = {obs.corrected.jacobi:.6f}; targets "
                f"only: C in [{rng['targets'][0]:.6f}, {rng['targets'][1]:.6f}]; all other rows (corrected): C in "
                f"[{rng['others'][0]:.6f}, {rng['others'][1]:.6f}]")

    def groups_report(self) -> str:
        """How many distinct orbits, where they cross and their periods, against the family drawn."""
        cross = np.array([g.crossing_km for g in self.groups])
        period = np.array([g.orbit.period_days for g in self.groups])
        return (f"W&J DROs: {len(self.groups)} distinct orbits, x-axis crossings {cross.min():.0f} to "
                f"{cross.max():.0f} km from the Moon (spread {np.ptp(cross):.0f} km), periods {period.min():.3f}-"
                f"{period.max():.3f} d; family drawn: periods {min(o.period_days for o in self.family):.1f}-"
                f"{max(o.period_days for o in self.family):.1f} d")


def _group_rows(system, checks) -> tuple:
    by_state = {}
    for c in checks:
        by_state.setdefault((c.x0, c.vy0), []).append(c)
    x_moon = system.secondary_position[0]
    groups = [DroGroup(tuple(g), float((g[0].x0 - x_moon) * system.length_unit_km)) for g in by_state.values()]
    return tuple(sorted(groups, key=lambda g: g.checks[0].x0))


def dro_table_study(system: CR3BP, n_members: int, *, zoom_margin_km: float = 1500.0, n_zoom: int = 12
                    ) -> DroTableStudy:
    """Verify every printed row of Tables 2 and 4, group the rows into distinct orbits, and continue the DRO family
    (``n_members`` members from 0.95 to 0.70 LU; ``n_zoom`` members across the printed orbits' crossings, padded by
    ``zoom_margin_km`` either side)."""
    check_system(system)
    n_members = validation.integer(n_members, "n_members", minimum=2)
    margin = validation.positive(zoom_margin_km, "zoom_margin_km")
    n_zoom = validation.integer(n_zoom, "n_zoom", minimum=2)
    checks = tuple(reference.verify_table_row(system, row) for row in reference.load_wolf_jones_table())
    groups = _group_rows(system, checks)
    family = tuple(orbits.dro_family(system, np.linspace(0.95, 0.70, n_members)))
    cross = [g.crossing_km for g in groups]
    zoom_x0 = (np.linspace(max(cross) + margin, min(cross) - margin, n_zoom) / system.length_unit_km
               + system.secondary_position[0])
    zoom = tuple(orbits.dro_family(system, zoom_x0, seed=groups[-1].orbit.x0))
    rounding = tuple(reference.rounding_bound(system, c) for c in checks)
    return DroTableStudy(checks, groups, family, zoom, system, rounding)


# ---------------------------------------------------------------------------------------------------------------
# How tightly the printed rows pin mu
# ---------------------------------------------------------------------------------------------------------------
def mu_trials(system: CR3BP, step: float = 1e-9) -> tuple:
    """The adopted :math:`\\mu`, its neighbours ``mu +- step`` and the published values :data:`PUBLISHED_MU`."""
    check_system(system)
    step = validation.positive(step, "step")
    return (system.mu, system.mu + step, system.mu - step, *PUBLISHED_MU)


@dataclass(frozen=True)
class MuClosureStudy:
    """Largest closure of the rows periodic as printed, per trial mass ratio.

    Attributes
    ----------
    adopted : float
        The system's :math:`\\mu`.
    mus : tuple of float
        Trial values (the first is the adopted one).
    closures : tuple of float
        Largest :math:`\\|x(T) - x_0\\|` (LU, LU/TU) over the rows, per trial.
    tolerance : float
        Closure criterion (``reference.CLOSURE_TOL``).
    """

    adopted: float
    mus: tuple
    closures: tuple
    tolerance: float

    @property
    def closure(self) -> dict:
        """Trial :math:`\\mu` -> largest closure."""
        return dict(zip(self.mus, self.closures))

    @property
    def adopted_closure(self) -> float:
        return self.closure[self.adopted]

    @property
    def pinned(self) -> bool:
        """The rows close at the adopted value and fail for every trial at least ``MU_PIN_OFFSET`` away."""
        return bool(self.adopted_closure < self.tolerance
                    and all(cl >= self.tolerance for m, cl in self.closure.items()
                            if abs(m - self.adopted) >= MU_PIN_OFFSET))

    def trials_text(self) -> str:
        """``d mu -> closure`` for every trial but the adopted value."""
        return ", ".join(f"{m - self.adopted:+.1e} -> {cl:.1e}" for m, cl in self.closure.items() if m != self.adopted)

    def report(self) -> str:
        lines = [f"largest closure of the printed periodic rows (criterion CLOSURE_TOL = {self.tolerance:.0e}):"]
        for mu, cl in self.closure.items():
            lines.append(f"  mu = {mu:.15f} (d mu = {mu - self.adopted:+.1e}): {cl:.1e}  "
                         f"{'closes' if cl < self.tolerance else 'fails'}")
        return "\n".join(lines)


def mu_closure_study(system: CR3BP, mus=None) -> MuClosureStudy:
    """Propagate every row periodic as printed (all but the observer's start) in systems that differ only in
    :math:`\\mu` and keep each trial's largest closure.  ``mus`` defaults to :func:`mu_trials`; the system's own
    :math:`\\mu` is always tried first."""
    check_system(system)
    trials = mu_trials(system) if mus is None else tuple(
        validation.positive(m, "mus") for m in validation.as_array(mus, "mus", ndim=(1,), min_size=1))
    if system.mu not in trials:
        trials = (system.mu, *trials)
    rows = [r for r in reference.load_wolf_jones_table() if r.label != "observer_t0"]
    closures = tuple(max(reference.verify_table_row(dataclasses.replace(system, mu=float(mu)), r).raw_closure
                         for r in rows) for mu in trials)
    return MuClosureStudy(system.mu, tuple(float(m) for m in trials), closures, reference.CLOSURE_TOL)


# ---------------------------------------------------------------------------------------------------------------
# The day counts of the windows against the two readings of the time unit
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class WindowStudy:
    """The windows of both test cases in days, for each reading of the time unit.

    Attributes
    ----------
    period_tu : float
        Period of the observer's (corrected) DRO, TU.
    units_days : dict of str -> float
        Each reading of the time unit (``"standard"``, ``"P_synodic/2pi"``), days.
    windows : dict of str -> ((float, float), (float, float))
        Case 1 and case 2 windows per reading, days.
    tolerance_days : float
        Tolerance on each window end, days.
    """

    period_tu: float
    units_days: dict
    windows: dict
    tolerance_days: float

    def miss(self, reading: str) -> float:
        """Largest distance of a window end from the text's 12, 23, 17 and 32 days, for one reading, days."""
        w1, w2 = self.windows[reading]
        return max(abs(a - b) for a, b in zip(w1 + w2, PAPER_WINDOWS_DAYS[0] + PAPER_WINDOWS_DAYS[1]))

    @property
    def case1(self) -> tuple:
        """Test case 1's window with the standard unit, days."""
        return self.windows["standard"][0]

    @property
    def case1_misses(self) -> tuple:
        """(start, end) distance of test case 1's window from the text's 12 and 23 days (standard unit), days."""
        return tuple(abs(a - b) for a, b in zip(self.case1, PAPER_WINDOWS_DAYS[0]))

    @property
    def period_days(self) -> float:
        """The observer's DRO period with the standard unit, days."""
        return self.period_tu * self.units_days["standard"]

    @property
    def fitting_periods(self) -> tuple:
        """(shortest, longest) period, days, for which [3P/4, 3P/2] meets both 12 and 23 days within the
        tolerance."""
        (a, b), tol = PAPER_WINDOWS_DAYS[0], self.tolerance_days
        return max((a - tol) * 4 / 3, (b - tol) * 2 / 3), min((a + tol) * 4 / 3, (b + tol) * 2 / 3)

    @property
    def standard_fits_better(self) -> bool:
        return bool(self.miss("standard") < self.miss("P_synodic/2pi"))

    def report(self) -> str:
        lines = []
        for reading, tu_d in self.units_days.items():
            (a1, b1), (a2, b2) = self.windows[reading]
            lines.append(f"time unit {reading:14s} = {tu_d:.4f} d: P = {self.period_tu * tu_d:.2f} d; case 1 window "
                         f"{a1:.1f}-{b1:.1f} d, case 2 window {a2:.1f}-{b2:.1f} d; largest miss of the paper's 12, "
                         f"23, 17, 32 d: {self.miss(reading):.1f} d")
        (a, b) = PAPER_WINDOWS_DAYS[0]
        lines.append(f"ratio of the window ends: paper {b:g}/{a:g} = {b / a:.3f}; [3P/4, 3P/2] gives 2 for any P and "
                     "time unit")
        return "\n".join(lines)


def window_study(system: CR3BP, period_tu: float, *, tolerance_days: float = WINDOW_TOL_DAYS) -> WindowStudy:
    """Test cases 1 and 2's windows, :math:`[3P/4, 3P/2]` and :math:`[P, 2P]` of the observer's DRO period
    ``period_tu`` (TU), in days for the standard time unit of ``system`` and for the literal reading
    :math:`P_{synodic}/2\\pi` of Wolf & Jones' words."""
    check_system(system)
    period_tu = validation.positive(period_tu, "period_tu")
    tol = validation.positive(tolerance_days, "tolerance_days")
    units = {"standard": system.time_unit_days, "P_synodic/2pi": SYNODIC_MONTH_DAYS / (2 * np.pi)}
    windows = {name: tuple((f0 * (period_tu * tu_d), f1 * (period_tu * tu_d)) for f0, f1 in WINDOW_FRACTIONS)
               for name, tu_d in units.items()}
    return WindowStudy(period_tu, units, windows, tol)

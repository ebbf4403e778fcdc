r"""Notebook 11's studies (Nychka & Bhattacharya, §III-IV, Fig. 2, Eq. 24): each set-up of the chapter as a function
that returns a frozen result.

The methods (LPV model, the LMIs of Theorems 1 and 2, the independent verification) live in
:mod:`cislunar.estimation.lpv`; this module ties them to the paper's set-up (its bound, the theta1 sensors, the
2:1 resonant orbit of :mod:`.scenarios`) and runs what the chapter reports: the exactness checks of Eqs. 20-23,
the designs and their solver-independence, the H-infinity bandwidth study, the verification, the objective-norm
sweep, the Eq. 24 allowances, the trade curve against gamma and the sensitivity study over what the paper leaves
unstated.

Units: gamma and positions in LU, times in TU (minutes where a name says ``_min``), angles in deg, precisions
:math:`\kappa` per unit sensor output (H2: TU^-1/2).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, EARTH_MOON, check_system
from cislunar.estimation import lpv
from cislunar.papers.nychka_bhattacharya.scenarios import (
    GAMMA,
    POLE_RADIUS,
    RESONANT_CANDIDATES,
    THETA1_SENSORS,
    Scenario,
    paper_scenario,
)
from cislunar.utils import validation
from cislunar.utils.montecarlo import map_tasks

__all__ = [
    "H2_BAND_DEG",
    "HINF_BAND_DEG",
    "NORMS",
    "OBJECTIVES",
    "Allowances",
    "BandwidthStudy",
    "Designs",
    "Exactness",
    "ObjectiveStudy",
    "SensitivityReading",
    "SensitivityStudy",
    "SolverChecks",
    "TradeCurve",
    "allowances",
    "bandwidth_study",
    "exactness_checks",
    "objective_norm_study",
    "paper_designs",
    "read_sensitivity",
    "sensitivity_study",
    "solver_independence",
    "trade_curve",
    "verify_designs",
]

NORMS = ("h2", "hinf")
#: The objectives of :func:`objective_norm_study`: :math:`\min\|\beta\|_p` for p = 1, 2, inf.
OBJECTIVES = ("l1", "l2", "linf")
#: The paper's "around 0.1 deg" (H2) and "0.08 deg" (H-infinity) as bands of their printed digits, deg.
H2_BAND_DEG = (0.05, 0.15)
HINF_BAND_DEG = (0.075, 0.085)


def _minutes(system) -> float:
    return system.time_unit_s / 60.0


# ------------------------------------------------------------------------------------------- Eqs. 20-23
@dataclass(frozen=True)
class Exactness:
    """Largest errors of the LPV forms against the nonlinear model at random states.

    Attributes
    ----------
    n_states : int
    dynamics : float
        Max relative :math:`|A(\\rho)x + b(\\rho) - f(x)|` (Eqs. 21/23 against Eq. 20).
    sensors_eq22 : float
        Max :math:`|C(\\rho)x + d(\\rho) - y(x)|` with Eq. 22's :math:`d`.
    sensors_eq23 : float
        The same with Eq. 23's :math:`d` as printed.
    triangulation : float
        Max relative error of :math:`\\rho` recovered from the two angles (law of sines).
    """

    n_states: int
    dynamics: float
    sensors_eq22: float
    sensors_eq23: float
    triangulation: float


def exactness_checks(model: lpv.CR3BPLPV, n_states: int, rng: np.random.Generator) -> Exactness:
    """Eqs. 20-23 checked at ``n_states`` random planar states (positions in [-1.5, 1.5] LU, velocities in
    [-2, 2] LU/TU) drawn with ``rng``."""
    model = validation.instance(model, "model", lpv.CR3BPLPV)
    n = validation.integer(n_states, "n_states", minimum=1)
    rng = validation.rng(rng, "rng")
    states = np.column_stack([rng.uniform(-1.5, 1.5, (n, 2)), rng.uniform(-2, 2, (n, 2))])
    f_nl = model.f(states)
    err_dyn = np.max(np.abs(model.lpv_rhs(states) - f_nl) / np.maximum(1.0, np.abs(f_nl)))
    y_nl = model.measure(states)
    rho = model.rho(states)
    err_22 = np.max(np.abs(model.lpv_measure(states) - y_nl))
    y_23 = np.einsum("nij,nj->ni", model.C(rho), states) + model.d_as_printed_eq23(rho)
    err_23 = np.max(np.abs(y_23 - y_nl))
    err_tri = np.max(np.abs(model.rho_from_angles(*model.angles(states)) - rho) / np.abs(rho).clip(1e-3))
    return Exactness(n, float(err_dyn), float(err_22), float(err_23), float(err_tri))


# --------------------------------------------------------------------------------------- the designs
@dataclass(frozen=True)
class Designs:
    """The chapter's designs at one gamma: all six sensors offered (Fig. 2) and the theta1-only problems (the
    comparison rows), H2 and bandwidth-bounded H-infinity.

    Attributes
    ----------
    gamma, pole_radius : float
        Bound (LU) and the H-infinity bandwidth bound R (1/TU).
    lmi_all, lmi : dict of str to PrecisionLMI
        The built problems by norm (six sensors; theta1 only), re-usable for sweeps.
    all, theta1 : dict of str to ObserverDesign
        Their solutions by norm.
    """

    gamma: float
    pole_radius: float
    lmi_all: dict
    lmi: dict
    all: dict
    theta1: dict


def paper_designs(scenario: Scenario, gamma: float = GAMMA, pole_radius: float = POLE_RADIUS) -> Designs:
    """Build and solve Theorems 1 and 2 at ``gamma`` on the vertices of ``scenario.box``."""
    scenario = validation.instance(scenario, "scenario", Scenario)
    gamma = validation.positive(gamma, "gamma")
    R = validation.positive(pole_radius, "pole_radius")
    V = scenario.box.vertices()
    model = scenario.model
    hinf_all = lpv.PrecisionLMI.for_cr3bp(model, V, "hinf", pole_radius=R)
    # the six-sensor H-infinity problem ends optimal_inaccurate at its default scaling and optimal at the first
    # scaling PrecisionLMI.solve retries (variable scale 100, velocity-balanced states): start there, the same
    # problem object and solve as the retry's, one failed solve fewer
    lmi_all = {"h2": lpv.PrecisionLMI.for_cr3bp(model, V, "h2"),
               "hinf": hinf_all.rescaled(lpv.RETRY_SCALINGS[0][0], hinf_all.balanced_state_scale)}
    d_all = {n: lmi_all[n].solve(gamma) for n in NORMS}
    lmi1 = {"h2": lpv.PrecisionLMI.for_cr3bp(model, V, "h2", sensors=THETA1_SENSORS),
            "hinf": lpv.PrecisionLMI.for_cr3bp(model, V, "hinf", sensors=THETA1_SENSORS, pole_radius=R)}
    d1 = {n: lmi1[n].solve(gamma) for n in NORMS}
    return Designs(gamma, R, lmi_all, lmi1, d_all, d1)


def _pole_kw(norm, R):
    return {"pole_radius": R} if norm == "hinf" else {}


@dataclass(frozen=True)
class SolverChecks:
    """The theta1-only precisions re-solved with a tighter tolerance (1e-9), a tenfold smaller strictness margin
    (1e-9) and another variable scaling (3).

    Attributes
    ----------
    deviation : dict of str to float
        Largest relative change of :math:`\\kappa_{\\sin\theta_1}` by norm.
    statuses : dict of str to list of str
        Solver statuses of the three re-solves by norm.
    """

    deviation: dict
    statuses: dict


def solver_independence(scenario: Scenario, designs: Designs) -> SolverChecks:
    """Re-solve each theta1-only problem under three settings that must not move the answer."""
    scenario = validation.instance(scenario, "scenario", Scenario)
    designs = validation.instance(designs, "designs", Designs)
    V, g = scenario.box.vertices(), designs.gamma
    dev, stat = {}, {}
    for norm in NORMS:
        kw = _pole_kw(norm, designs.pole_radius)
        alt = [designs.lmi[norm].solve(g, tol=1e-9),
               lpv.PrecisionLMI.for_cr3bp(scenario.model, V, norm, sensors=THETA1_SENSORS, eps=1e-9, **kw).solve(g),
               lpv.PrecisionLMI.for_cr3bp(scenario.model, V, norm, sensors=THETA1_SENSORS, variable_scale=3.0,
                                          **kw).solve(g)]
        dev[norm] = float(max(abs(a.kappa[0] / designs.theta1[norm].kappa[0] - 1) for a in alt))
        stat[norm] = [a.status for a in alt]
    return SolverChecks(dev, stat)


@dataclass(frozen=True)
class BandwidthStudy:
    r"""The theta1-only H-infinity problem against the bandwidth bound R.

    Attributes
    ----------
    radii : ndarray (k,)
        Bounds R, 1/TU.
    noise_deg, gain_norm : ndarray (k,)
        Eq. 24 allowance of :math:`\sin\theta_1` (deg) and :math:`\|L\|_2` of each optimum.
    status : tuple of str
    r13_max : float
        Largest Earth distance on the orbit, LU.
    limit_deg : float
        The unbounded-gain limit :math:`\sin^{-1}(\gamma/\max r_{13})`, deg.
    """

    radii: np.ndarray
    noise_deg: np.ndarray
    gain_norm: np.ndarray
    status: tuple
    r13_max: float
    limit_deg: float


def bandwidth_study(scenario: Scenario, radii, gamma: float = GAMMA) -> BandwidthStudy:
    """Solve the theta1-only Theorem 2 for each bandwidth bound in ``radii`` (1/TU)."""
    scenario = validation.instance(scenario, "scenario", Scenario)
    R = validation.as_array(radii, "radii", ndim=(1,), min_size=1)
    if np.any(R <= 0):
        raise ValueError(f"radii must be positive (1/TU); got {R}")
    gamma = validation.positive(gamma, "gamma")
    V = scenario.box.vertices()
    ds = [lpv.PrecisionLMI.for_cr3bp(scenario.model, V, "hinf", sensors=THETA1_SENSORS, pole_radius=float(r))
          .solve(gamma) for r in R]
    r13max = float(1.0 / scenario.box.lower[2])
    return BandwidthStudy(R, np.array([d.noise_deg[0] for d in ds]), np.array([d.gain_norm for d in ds]),
                          tuple(d.status for d in ds), r13max, float(np.degrees(np.arcsin(gamma / r13max))))


def verify_designs(scenario: Scenario, designs: Designs, n_samples: int, rng: np.random.Generator) -> dict:
    """:func:`cislunar.estimation.lpv.verify_observer` of the full gains, theta1-only then six-sensor, H2 then
    H-infinity (in that order of draws from ``rng``).  Keys ``"h2"``, ``"hinf"``, ``"h2 (6 sensors)"``,
    ``"hinf (6 sensors)"``."""
    scenario = validation.instance(scenario, "scenario", Scenario)
    designs = validation.instance(designs, "designs", Designs)
    n_samples = validation.integer(n_samples, "n_samples", minimum=1)
    rng = validation.rng(rng, "rng")
    out = {}
    for key, d in (("h2", designs.theta1["h2"]), ("hinf", designs.theta1["hinf"]),
                   ("h2 (6 sensors)", designs.all["h2"]), ("hinf (6 sensors)", designs.all["hinf"])):
        out[key] = lpv.verify_observer(scenario.model, d, scenario.box, n_samples, rng, L=d.L)
    return out


# ----------------------------------------------------------------------------------- objective norm
@dataclass(frozen=True)
class ObjectiveStudy:
    r"""The six-sensor problems under :math:`\min\|\beta\|_p`, p = 1, 2, inf.

    Attributes
    ----------
    designs : dict of (str, str) to ObserverDesign
        Keyed ``(objective, norm)``, objective in ``("l1", "l2", "linf")``.
    sparsity_tol : float
        A sensor is used when :math:`\beta_i` exceeds this fraction of the largest.
    same_tol : float
        "Identical" precisions: relative difference below this.
    """

    designs: dict
    sparsity_tol: float
    same_tol: float

    def _solved(self, objective: str) -> str:
        objective = validation.choice(objective, "objective", OBJECTIVES)
        if any((objective, n) not in self.designs for n in NORMS):
            solved = sorted({k[0] for k in self.designs})
            raise ValueError(f"objective {objective!r} was not solved in this study (objective_norm_study's "
                             f"objectives); solved: {solved}")
        return objective

    def same_theta1(self, objective: str) -> bool:
        r""":math:`|\kappa_{\sin}/\kappa_{\cos} - 1| <` ``same_tol`` for both norms under ``objective``."""
        objective = self._solved(objective)
        return all(abs(self.designs[(objective, n)].kappa[0] / self.designs[(objective, n)].kappa[1] - 1)
                   < self.same_tol for n in NORMS)

    @property
    def only_theta1(self) -> bool:
        """With p = 1 both theorems keep sin and cos theta1 and nothing else."""
        return all(self.designs[("l1", n)].used[:2].all() and not self.designs[("l1", n)].used[2:].any()
                   for n in NORMS)

    def all_used(self, objective: str) -> bool:
        """Both theorems use all six sensors under ``objective``."""
        objective = self._solved(objective)
        return all(self.designs[(objective, n)].used.all() for n in NORMS)

    @property
    def six_equal_linf(self) -> bool:
        """With p = inf the six precisions agree within ``same_tol`` (relative), for both norms."""
        self._solved("linf")
        return all(np.ptp(self.designs[("linf", n)].kappa) < self.same_tol * self.designs[("linf", n)].kappa.max()
                   for n in NORMS)


def objective_norm_study(scenario: Scenario, designs: Designs, *, sparsity_tol: float = 1e-4,
                         same_tol: float = 1e-3, objectives=("l2", "linf")) -> ObjectiveStudy:
    """Solve the six-sensor problems with p = 2 and p = inf (p = 1 is ``designs.all``).

    ``objectives`` (a subset of ``("l2", "linf")``, at least one) selects which are solved (each is two 64-vertex
    solves; the tests ask for one).
    """
    scenario = validation.instance(scenario, "scenario", Scenario)
    designs = validation.instance(designs, "designs", Designs)
    sparsity_tol = validation.in_range(sparsity_tol, "sparsity_tol", 0.0, 1.0)
    same_tol = validation.positive(same_tol, "same_tol")
    objectives = validation.one_or_many(objectives, "objectives", str, "objective name")
    objectives = [validation.choice(o, "objectives", ("l2", "linf")) for o in objectives]
    V = scenario.box.vertices()
    out = {("l1", n): designs.all[n] for n in designs.all}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # p = inf, Hinf may end optimal_inaccurate: reported
        for obj in ("l2", "linf"):
            if obj not in objectives:
                continue
            for n in NORMS:
                lmi = lpv.PrecisionLMI.for_cr3bp(scenario.model, V, n, objective=obj, **_pole_kw(n, designs.pole_radius))
                if (obj, n) == ("l2", "hinf"):
                    # p = 2 H-infinity ends optimal_inaccurate at its default scaling (boxes from 600 to 4000 orbit
                    # samples), as p = 1 does (paper_designs); start at the first scaling solve() retries, which then
                    # tries the default one later: the same problem objects and solves, the same first 'optimal'
                    # design.  Quick box (600): optimal at once, one failed 64-vertex solve fewer; full box (4000):
                    # optimal only at (30, balanced), the fifth either way (no saving)
                    lmi = lmi.rescaled(lpv.RETRY_SCALINGS[0][0], lmi.balanced_state_scale)
                # p = inf, H-infinity: no scaling of the retry list reaches optimal (all end optimal_inaccurate, and
                # solve() then returns the first, default-scaled solution): solved once, its status reported
                out[(obj, n)] = lmi.solve(designs.gamma, sparsity_tol=sparsity_tol,
                                          retry=not (obj == "linf" and n == "hinf"))
    return ObjectiveStudy(out, sparsity_tol, same_tol)


# ------------------------------------------------------------------------------------------- Eq. 24
@dataclass(frozen=True)
class Allowances:
    r"""Eq. 24 allowances of the theta1-only designs and the two readings of the H2 number.

    Attributes
    ----------
    h2_deg, hinf_deg : float
        :math:`\sin^{-1}(1/\kappa)` of the theta1 channels (the smaller of sin, cos), deg; H2 read as an angle
        (it is a white-noise intensity, deg TU^1/2).
    kappa_h2, kappa_hinf : float
        Smaller precision of the theta1 channels (H2: of the H2 design; H-infinity: of sin theta1).
    dt_01 : float
        Sampling interval at which H2 allows exactly 0.1 deg per sample, :math:`1/(\kappa\sin 0.1°)^2`, TU.
    dt_eq : float
        H2 per sample exceeds H-infinity for sampling intervals below this, TU.
    h2_literal_deg : float
        H2 with Eq. 8b read literally (trace < gamma, i.e. the bound :math:`\sqrt\gamma`), deg.
    hinf_literal_deg : float
        H-infinity with the printed :math:`\kappa = \sqrt{\beta/\gamma}`, deg.
    minutes_per_tu : float
    """

    h2_deg: float
    hinf_deg: float
    kappa_h2: float
    kappa_hinf: float
    dt_01: float
    dt_eq: float
    h2_literal_deg: float
    hinf_literal_deg: float
    minutes_per_tu: float

    @property
    def kappa_paper(self) -> dict:
        """The precisions Eq. 24 implies for the paper's 0.1 deg (H2) and 0.08 deg (H-infinity)."""
        return {"h2": 1.0 / np.sin(np.radians(0.1)), "hinf": 1.0 / np.sin(np.radians(0.08))}

    @property
    def kappa_band_hinf(self) -> tuple:
        """Precisions whose Eq. 24 angle lies in the printed-digit band of 0.08 deg."""
        return tuple(1.0 / np.sin(np.radians(HINF_BAND_DEG[::-1])))


def allowances(designs: Designs, system: CR3BP = EARTH_MOON) -> Allowances:
    """Eq. 24 read both ways for the theta1-only designs (solves Eq. 8b's literal reading once)."""
    designs = validation.instance(designs, "designs", Designs)
    minutes = _minutes(check_system(system, "system"))
    d = designs.theta1
    noise = {n: float(np.min(d[n].noise_deg[:2])) for n in NORMS}
    k2 = float(np.min(d["h2"].kappa[:2]))
    dt_01 = 1.0 / (k2 * np.sin(np.radians(0.1))) ** 2
    dt_eq = 1.0 / (k2 * np.sin(np.radians(noise["hinf"]))) ** 2
    g = designs.gamma
    h2_lit = float(designs.lmi["h2"].solve(np.sqrt(g)).noise_deg[0])
    hinf_lit = float(np.degrees(np.arcsin(np.sqrt(g) / d["hinf"].kappa[0])))
    return Allowances(noise["h2"], noise["hinf"], k2, float(d["hinf"].kappa[0]), float(dt_01), float(dt_eq),
                      h2_lit, hinf_lit, minutes)


# ------------------------------------------------------------------------------------- trade curve
@dataclass(frozen=True)
class TradeCurve:
    """Required theta1 precision against gamma (theta1-only problems re-solved at each gamma).

    Attributes
    ----------
    gammas : ndarray (k,)
        Bounds, LU.
    kappa, noise_deg : dict of str to ndarray (k,)
        :math:`\\kappa_{\\sin\\theta_1}` and its Eq. 24 angle by norm (NaN where infeasible).
    slope : dict of str to float
        Log-log slope of kappa against gamma.
    """

    gammas: np.ndarray
    kappa: dict
    noise_deg: dict
    slope: dict


def trade_curve(designs: Designs, gammas) -> TradeCurve:
    """Sweep gamma on the built theta1-only problems (``gamma`` enters through the disturbance ratio: no rebuild)."""
    designs = validation.instance(designs, "designs", Designs)
    g = validation.as_array(gammas, "gammas", ndim=(1,), min_size=2)
    if np.any(g <= 0):
        raise ValueError(f"gammas must be positive (LU); got {g}")
    kappa, noise = {}, {}
    for n in NORMS:
        sweep = lpv.gamma_sweep(designs.lmi[n], g)
        kappa[n] = np.array([np.nan if d is None else d.kappa[0] for d in sweep])
        noise[n] = np.array([np.nan if d is None else d.noise_deg[0] for d in sweep])
    slope = {n: float(np.polyfit(np.log(g), np.log(kappa[n]), 1)[0]) for n in NORMS}
    return TradeCurve(g, kappa, noise, slope)


# ------------------------------------------------------------------------------- sensitivity study
@dataclass(frozen=True)
class SensitivityStudy:
    r"""Allowable :math:`\theta_1` noise at one gamma over orbits, disturbance structures and levels.

    Array axes are ``(orbit, structure, level)``.  The precisions come from the :math:`\theta_1`-only problems
    (``sensors=[0, 1]``, the channels Eq. 24 uses and the :math:`\|\beta\|_1` optimum selects), whose LMIs depend
    only on :math:`\rho_1, \rho_2, \rho_3` (8 distinct vertices).  The sampling interval enters afterwards, through
    :meth:`h2_per_sample_deg`.

    Attributes
    ----------
    orbits : tuple of (p, q, perigee_radius)
    r13_max, period : ndarray (n_orbit,)
        Largest Earth distance (LU) and period (TU) of each orbit.
    structures : tuple of str
    levels : ndarray (n_level,)
        Disturbance levels :math:`S_d = \mathrm{level}\,I`.
    gamma, pole_radius : float
        Bound (LU) and the H-infinity bandwidth bound R (1/TU).
    h2_kappa, hinf_kappa : ndarray
        Precision of the :math:`\theta_1` channels (the smaller of sin and cos; NaN where infeasible).
    h2_status, hinf_status : ndarray of str
    h2_gain, hinf_gain : ndarray
        :math:`\|L\|_2` of each design.
    seconds : float
        Wall-clock time of the study.
    """

    orbits: tuple
    r13_max: np.ndarray
    period: np.ndarray
    structures: tuple
    levels: np.ndarray
    gamma: float
    pole_radius: float
    h2_kappa: np.ndarray
    hinf_kappa: np.ndarray
    h2_status: np.ndarray
    hinf_status: np.ndarray
    h2_gain: np.ndarray
    hinf_gain: np.ndarray
    seconds: float

    @property
    def h2_intensity_deg(self) -> np.ndarray:
        """H2 allowance read directly through Eq. 24 (a white-noise intensity, deg TU^1/2)."""
        return lpv.precision_to_noise_deg(np.nan_to_num(self.h2_kappa, nan=np.inf))

    @property
    def hinf_deg(self) -> np.ndarray:
        """H-infinity allowance through Eq. 24, deg."""
        return lpv.precision_to_noise_deg(np.nan_to_num(self.hinf_kappa, nan=np.inf))

    def h2_per_sample_deg(self, dt) -> np.ndarray:
        """H2 allowance per sample for sampling interval(s) ``dt`` (TU); broadcasts ``dt`` on a new last axis."""
        dt = validation.as_array(dt, "dt")
        if np.any(dt <= 0):
            raise ValueError("dt must be positive (TU)")
        k = np.nan_to_num(self.h2_kappa, nan=np.inf)[..., None] * np.sqrt(dt)
        out = lpv.precision_to_noise_deg(k)
        return out[..., 0] if dt.ndim == 0 else out

    def dt_for_h2(self, target_deg: float = 0.1) -> np.ndarray:
        """Sampling interval (TU) at which the H2 per-sample allowance equals ``target_deg``."""
        s = np.sin(np.radians(validation.in_range(target_deg, "target_deg", 0.0, 90.0, closed=False)))
        return 1.0 / (self.h2_kappa * s) ** 2

    @property
    def all_optimal(self) -> bool:
        """Every solve ended ``optimal``."""
        return bool(np.all(self.h2_status == "optimal") and np.all(self.hinf_status == "optimal"))


def _study_orbit(task):
    """One orbit of :func:`sensitivity_study` (module-level so process pools can pickle it)."""
    system, (p, q, rp), structures, levels, gamma, R, n_samples = task
    sc = paper_scenario(system, p=p, q=q, perigee_radius=rp, n_samples=n_samples)
    V = sc.box.vertices()
    shape = (len(structures), len(levels))
    res = {f"{n}_{k}": np.full(shape, np.nan) for n in NORMS for k in ("kappa", "gain")}
    res.update({f"{n}_status": np.full(shape, "not_run", dtype=object) for n in NORMS})
    for i, structure in enumerate(structures):
        dist = lpv.disturbance_model(structure, 1.0)
        for norm in NORMS:
            lmi = lpv.PrecisionLMI.for_cr3bp(sc.model, V, norm, disturbance=dist, sensors=[0, 1],
                                         pole_radius=R if norm == "hinf" else None)
            for j, level in enumerate(levels):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    try:
                        d = lmi.solve(gamma, disturbance_scale=float(level))
                    except lpv.InfeasibleLMIError as exc:
                        res[f"{norm}_status"][i, j] = exc.status
                        continue
                res[f"{norm}_kappa"][i, j] = float(np.min(d.kappa[:2]))
                res[f"{norm}_gain"][i, j] = d.gain_norm
                res[f"{norm}_status"][i, j] = d.status
    res["r13_max"] = float(1.0 / sc.box.lower[2])
    res["period"] = sc.orbit.period
    return res


def sensitivity_study(gamma: float = 0.0013, *, orbits=RESONANT_CANDIDATES, structures=lpv.DISTURBANCE_STRUCTURES,
                      levels=(0.0, 1e-4, 1e-3, 1e-2), pole_radius: float = 1000.0, n_samples: int = 1000,
                      system: CR3BP = EARTH_MOON, executor=None, progress: bool = False) -> SensitivityStudy:
    r"""Where do the paper's 0.1 deg (H2) and 0.08 deg (H-infinity) come from?  Solve both theorems over the inputs
    the paper leaves unstated.

    For every resonant orbit (its :math:`\rho` box from ``n_samples`` points over one period), disturbance
    structure (:func:`~cislunar.estimation.lpv.disturbance_model`) and level, the :math:`\theta_1`-only H2 problem and the
    bandwidth-bounded H-infinity problem are solved at ``gamma``.  Each (orbit, structure, norm) problem is built
    once; the level only rescales the disturbance part of its data.

    Parameters
    ----------
    gamma : float
        Bound, LU.
    orbits : sequence of (p, q, perigee_radius)
        Planar resonances (see :data:`~cislunar.papers.nychka_bhattacharya.scenarios.RESONANT_CANDIDATES`).
    structures : sequence of str
        Disturbance structures.
    levels : array_like
        Disturbance levels (>= 0).
    pole_radius : float
        H-infinity bandwidth bound R, 1/TU (makes the minimum attained; see :class:`PrecisionLMI`).
    n_samples : int
        Samples per orbit period bounding :math:`\rho`.
    system : CR3BP
    executor : concurrent.futures.Executor or dask.distributed.Client, optional
        Runs the orbits (one task each) through :func:`cislunar.utils.montecarlo.map_tasks`; default serial
        (:func:`cislunar.utils.executors.open_executor` builds one from a notebook's ``WORKERS`` and ``SCHEDULER``).
        Results do not depend on it.
    progress : bool
        Show a progress bar over the orbits.

    Returns
    -------
    SensitivityStudy
    """
    gamma = validation.positive(gamma, "gamma")
    system = check_system(system, "system")
    try:
        orbits = tuple((validation.integer(o[0], "orbits p"), validation.integer(o[1], "orbits q"),
                        validation.positive(o[2], "orbits perigee_radius")) for o in orbits)
    except (TypeError, IndexError) as exc:
        raise validation.ArgumentTypeError("orbits must be a sequence of (p, q, perigee_radius) tuples") from exc
    if not orbits:
        raise ValueError("orbits must hold at least one (p, q, perigee_radius)")
    structures = tuple(validation.choice(s, "structures", lpv.DISTURBANCE_STRUCTURES)
                       for s in validation.one_or_many(structures, "structures", str, "disturbance structure name"))
    lv = validation.as_array(levels, "levels", ndim=(1,), min_size=1)
    if np.any(lv < 0):
        raise ValueError(f"levels must be >= 0; got {lv}")
    R = validation.positive(pole_radius, "pole_radius")
    n_samples = validation.integer(n_samples, "n_samples", minimum=10)
    progress = validation.boolean(progress, "progress")
    tasks = [(system, o, structures, tuple(lv), gamma, R, n_samples) for o in orbits]
    t0 = time.perf_counter()
    results = map_tasks(_study_orbit, tasks, executor=executor, progress=progress, desc="sensitivity study (orbits)")
    stack = {k: np.stack([r[k] for r in results]) for k in results[0] if k not in ("r13_max", "period")}
    return SensitivityStudy(orbits=orbits, r13_max=np.array([r["r13_max"] for r in results]),
                            period=np.array([r["period"] for r in results]), structures=structures, levels=lv,
                            gamma=gamma, pole_radius=R, h2_kappa=stack["h2_kappa"], hinf_kappa=stack["hinf_kappa"],
                            h2_status=stack["h2_status"].astype(str), hinf_status=stack["hinf_status"].astype(str),
                            h2_gain=stack["h2_gain"], hinf_gain=stack["hinf_gain"],
                            seconds=time.perf_counter() - t0)


@dataclass(frozen=True)
class SensitivityReading:
    r"""Where the paper's numbers hold in a :class:`SensitivityStudy`.

    Attributes
    ----------
    names : tuple of str
        Orbit labels ``"p:q guess-rp r"``.
    level_index : int
        Index of the reference disturbance level (closest to 1e-3).
    dt_01, dt_eq : ndarray (orbit, structure, level)
        Sampling interval (TU) at which H2 allows 0.1 deg per sample; below which H2 per sample exceeds H-infinity.
    dt_lo, dt_hi : ndarray (orbit, structure, level)
        Window (TU) in which the H2 per-sample allowance lies in :data:`H2_BAND_DEG` and exceeds H-infinity.
    hinf_in_band : ndarray of bool (orbit, structure, level)
        H-infinity allowance in :data:`HINF_BAND_DEG` (half-open).
    all_hold : ndarray of bool
        ``hinf_in_band`` and a non-empty window.
    hits : tuple of (name, structure, level, dt_lo_min, dt_hi_min)
        The cases where all hold, windows in minutes.
    h2_intensity_in_band : bool
        The H2 allowance read as an angle lies in the H2 band somewhere.
    h2_intensity_max : float
        Largest H2 allowance read as an angle, deg.
    hinf_spread : float
        Largest relative change of the H-infinity allowance with the disturbance (structure and level).
    r13_band : tuple of float
        Largest Earth distances (LU) whose unbounded-gain limit falls in the H-infinity band.
    n_optimal : int
        Solves that ended ``optimal`` (of ``2 * h2_kappa.size``).
    minutes_per_tu : float
    """

    names: tuple
    level_index: int
    dt_01: np.ndarray
    dt_eq: np.ndarray
    dt_lo: np.ndarray
    dt_hi: np.ndarray
    hinf_in_band: np.ndarray
    all_hold: np.ndarray
    hits: tuple
    h2_intensity_in_band: bool
    h2_intensity_max: float
    hinf_spread: float
    r13_band: tuple
    n_optimal: int
    minutes_per_tu: float

    @property
    def orbits_in_band(self) -> list:
        """Labels of the orbits whose H-infinity allowance (first structure and level) lies in the band."""
        return [self.names[i] for i in np.nonzero(self.hinf_in_band[:, 0, 0])[0]]


def read_sensitivity(study: SensitivityStudy, *, reference_level: float = 1e-3,
                     system: CR3BP = EARTH_MOON) -> SensitivityReading:
    """Where, in ``study``, do H-infinity in [0.075, 0.085) deg, H2 per sample in [0.05, 0.15) deg and H2 > H-infinity
    hold together?"""
    study = validation.instance(study, "study", SensitivityStudy)
    reference_level = validation.positive(reference_level, "reference_level", allow_zero=True)
    minutes = _minutes(check_system(system, "system"))
    h2i, hinf = study.h2_intensity_deg, study.hinf_deg
    names = tuple(f"{p}:{q} guess-rp {rp:.2f}" for p, q, rp in study.orbits)
    j = int(np.argmin(np.abs(study.levels - reference_level)))
    dt01 = study.dt_for_h2(0.1)
    dteq = 1.0 / (study.h2_kappa * np.sin(np.radians(hinf))) ** 2
    lo = 1.0 / (study.h2_kappa * np.sin(np.radians(H2_BAND_DEG[1]))) ** 2
    hi = np.minimum(1.0 / (study.h2_kappa * np.sin(np.radians(H2_BAND_DEG[0]))) ** 2, dteq)
    ok_hinf = (hinf >= HINF_BAND_DEG[0]) & (hinf < HINF_BAND_DEG[1])
    ok_all = ok_hinf & (hi > lo)
    hits = tuple((names[i], study.structures[s_], float(study.levels[l_]), float(lo[i, s_, l_] * minutes),
                  float(hi[i, s_, l_] * minutes)) for i, s_, l_ in zip(*np.nonzero(ok_all)))
    n_opt = int(np.sum(study.h2_status == "optimal") + np.sum(study.hinf_status == "optimal"))
    band = (study.gamma / np.sin(np.radians(HINF_BAND_DEG[1])), study.gamma / np.sin(np.radians(HINF_BAND_DEG[0])))
    return SensitivityReading(
        names=names, level_index=j, dt_01=dt01, dt_eq=dteq, dt_lo=lo, dt_hi=hi, hinf_in_band=ok_hinf,
        all_hold=ok_all, hits=hits, h2_intensity_in_band=bool(np.any((h2i >= H2_BAND_DEG[0]) & (h2i < H2_BAND_DEG[1]))),
        h2_intensity_max=float(np.nanmax(h2i)), hinf_spread=float(np.nanmax(np.abs(hinf / hinf[:, :1, :1] - 1))),
        r13_band=(float(band[0]), float(band[1])), n_optimal=n_opt, minutes_per_tu=minutes)

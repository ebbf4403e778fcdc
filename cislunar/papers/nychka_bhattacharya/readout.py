r"""What notebooks 11 and 12 print, and the measurements behind their closing tables.

Each function takes the results of one section of a chapter (the frozen results of
:mod:`cislunar.papers.nychka_bhattacharya.sensing_precision` and :mod:`.observer_simulation`) and returns a
:class:`Readout`: the text the section prints and one :class:`Measurement` per claim key of
:mod:`cislunar.papers.nychka_bhattacharya.claims` (the measured value in the claim's units, how the row shows it and
its context).  The notebook judges them with :meth:`Readout.judged`, which calls ``Claim.judge`` for every row, so
the status words are computed by the rule of :mod:`cislunar.publish.claims`, never typed here.

Units: LU, TU (minutes where a text says ``min``), km where a text says ``km``, deg.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, EARTH_MOON, check_system
from cislunar.estimation import lpv
from cislunar.papers.nychka_bhattacharya import observer_simulation as obs
from cislunar.papers.nychka_bhattacharya import robust as rb
from cislunar.papers.nychka_bhattacharya import sensing_precision as sp
from cislunar.papers.nychka_bhattacharya.scenarios import Scenario
from cislunar.utils import validation

__all__ = [
    "Measurement",
    "Readout",
    # notebook 11
    "dynamics",
    "sensors",
    "scenario",
    "disturbance",
    "designs",
    "solver_checks",
    "bandwidth",
    "verification",
    "objective",
    "allowances",
    "trade_curve",
    "study_table",
    "study_verdict",
    # notebook 12
    "observer_gains",
    "allowance_at_dt",
    "measurements",
    "convergence",
    "convergence_time",
    "line_crossings",
    "converges",
    "comparison",
    "scheduling_error",
    "robust_designs",
    "window",
]


@dataclass(frozen=True)
class Measurement:
    """A measured value for one claim, how the row shows it, its context and (when it differs) why."""

    value: object
    shown: str | None = None
    note: str = ""
    reason: str = ""


@dataclass(frozen=True)
class Readout:
    """What one section prints (``text``, possibly empty) and its closing-table measurements by claim key."""

    text: str = ""
    rows: dict = field(default_factory=dict)

    def __str__(self) -> str:
        return self.text

    def judged(self, claims: dict) -> list:
        """``claims[key].judge(...)`` of every row, in order (the status is computed by the claim's rule)."""
        validation.instance(claims, "claims", dict)
        missing = [k for k in self.rows if k not in claims]
        if missing:
            raise KeyError(f"no declared claim for row(s) {missing}")
        return [claims[k].judge(m.value, shown=m.shown, note=m.note, reason=m.reason) for k, m in self.rows.items()]


def _km(system) -> float:
    return check_system(system, "system").length_unit_km


def _minutes(system) -> float:
    return check_system(system, "system").time_unit_s / 60.0


def _used(design) -> list:
    return [n for n, u in zip(lpv.SENSOR_NAMES, design.used) if u]


# =============================================================================================== notebook 11
def dynamics(ex: sp.Exactness) -> Readout:
    """Section 1: Eqs. 21/23 against the CR3BP vector field."""
    ex = validation.instance(ex, "ex", sp.Exactness)
    return Readout(
        f"max relative |A(rho)x + b(rho) - f(x)| over {ex.n_states} states: {ex.dynamics:.2e}",
        {"lpv_exact": Measurement(ex.dynamics, f"max rel. error {ex.dynamics:.1e}",
                                  "A(rho), b(rho) as printed; checked at random states")})


def sensors(ex: sp.Exactness) -> Readout:
    """Section 2: the sensor model of Eq. 22 against Eq. 23's printed d(rho), and the triangulation."""
    ex = validation.instance(ex, "ex", sp.Exactness)
    return Readout(
        f"Eq. 22: max |C x + d - y| = {ex.sensors_eq22:.2e};  Eq. 23 as printed: {ex.sensors_eq23:.3f}\n"
        f"rho from the two angles (law of sines): max relative error {ex.triangulation:.1e}",
        {"eq22_exact": Measurement(ex.sensors_eq22, f"max error {ex.sensors_eq22:.1e}",
                                   "rho5 = x, rho6 = y (undefined in paper)"),
         "eq23_d": Measurement(ex.sensors_eq23, f"error up to {ex.sensors_eq23:.2f}")})


def scenario(sc: Scenario) -> Readout:
    """Section 3: the orbit and the box of the scheduling parameters."""
    sc = validation.instance(sc, "sc", Scenario)
    box, r13, n_v = sc.box, sc.r13_range, sc.box.vertices().shape[0]
    lines = [box.source] + [f"  rho {name:8s}: [{lo:9.4f}, {hi:9.4f}]"
                            for name, lo, hi in zip(lpv.RHO_NAMES, box.lower, box.upper)]
    return Readout("\n".join(lines), {
        "orbit": Measurement(f"{sc.orbit.p}:{sc.orbit.q}, T = {sc.orbit.period:.4f} TU, r13 {r13[0]:.3f}-{r13[1]:.3f} "
                             "LU"),
        "vertices": Measurement(n_v, f"{n_v}", "2^6 box vertices of rho")})


#: Sun's gravitational parameter (km^3/s^2) and the Earth-Sun distance (km), for the solar tide of Section 4.
GM_SUN, D_SUN = 1.32712440018e11, 1.495978707e8


def disturbance(system: CR3BP = EARTH_MOON) -> Readout:
    """Section 4: the default disturbance level (1e-3 LU/TU^2) against the solar tidal acceleration the CR3BP
    ignores."""
    acc = check_system(system, "system").length_unit_km / system.time_unit_s**2  # 1 LU/TU^2 in km/s^2
    tide = 2 * GM_SUN * np.array([0.3, 1.0]) * system.length_unit_km / D_SUN**3  # km/s^2 at r13 = 0.3, 1 LU
    return Readout(f"default S_d = 1e-3 LU/TU^2 = {1e-3 * acc:.1e} km/s^2; solar tide 2 GM_sun r / d^3 at "
                   f"r13 = 0.3-1 LU: {tide[0]:.1e}-{tide[1]:.1e} km/s^2 = {tide[0] / acc:.4f}-{tide[1] / acc:.4f} "
                   "LU/TU^2")


def designs(D: sp.Designs) -> Readout:
    """Section 4: the designs of both theorems, six sensors and theta1 only, and their solver status."""
    D = validation.instance(D, "D", sp.Designs)
    lines = [f"{norm:4s} {label:12s}: status {d.status}, |L| = {d.gain_norm:7.1f}, kappa(sin, cos th1) = "
             f"{np.array2string(d.kappa[:2], precision=2)}, Eq. 24 noise {d.noise_deg[0]:.5f} deg; sensors used: "
             f"{_used(d)}"
             for norm in sp.NORMS for label, d in (("all sensors", D.all[norm]), ("theta1 only", D.theta1[norm]))]
    how = {"h2": "Clarabel, no gain bound needed",
           "hinf": f"Clarabel; Hinf with bandwidth bound R = {D.pole_radius:.0f}/TU"}
    rows = {f"{n}_status": Measurement(
        D.all[n].optimal and D.theta1[n].optimal,
        f"{D.all[n].status} (6 sensors), {D.theta1[n].status} (theta1); |L| = {D.theta1[n].gain_norm:.0f}", how[n])
        for n in sp.NORMS}
    return Readout("\n".join(lines), rows)


def solver_checks(checks: sp.SolverChecks) -> Readout:
    """Section 5 (a): the theta1-only precisions under other solver settings."""
    checks = validation.instance(checks, "checks", sp.SolverChecks)
    lines, rows = [], {}
    for norm in sp.NORMS:
        dev, st = checks.deviation[norm], checks.statuses[norm]
        lines.append(f"{norm:4s}: tol 1e-9 / eps 1e-9 / scale 3: statuses {st}, max relative change of kappa {dev:.1e}")
        rows[f"{norm}_solver"] = Measurement(dev, f"max rel. change {dev:.0e} ({', '.join(st)})",
                                             "tolerance 1e-9, margin 1e-9, variable scale 3")
    return Readout("\n".join(lines), rows)


def bandwidth(bw: sp.BandwidthStudy) -> Readout:
    """Section 5 (b): the H-infinity precision against the bandwidth bound R."""
    bw = validation.instance(bw, "bw", sp.BandwidthStudy)
    lines = [f"R = {R:7.0f}/TU: {st:18s} noise {nd:.5f} deg, |L| = {g:9.1f}"
             for R, nd, g, st in zip(bw.radii, bw.noise_deg, bw.gain_norm, bw.status)]
    return Readout("\n".join(lines), {"bandwidth": Measurement(
        bw.noise_deg[-1], f"{bw.noise_deg[0]:.4f} deg (R={bw.radii[0]:.0f}) -> {bw.noise_deg[-1]:.4f} deg "
        f"(R={bw.radii[-1]:.0f}); limit {bw.limit_deg:.4f} deg", "the unbounded optimum is an infimum: gain grows like R")})


def verification(ver: dict, gamma: float) -> Readout:
    """Section 6: the independent verification of the four gains (:func:`sensing_precision.verify_designs`)."""
    validation.instance(ver, "ver", dict)
    gamma = validation.positive(gamma, "gamma")
    lines = [f"{key:16s}: {v.n_vertices} vertices + {v.n_samples} samples; max Re eig = {v.max_real_eig:.3f} /TU; "
             f"worst H2 = {v.worst_h2:.4e}, worst Hinf = {v.worst_hinf:.4e} (gamma {gamma}); passed: {v.passed}"
             for key, v in ver.items()]
    rows = {}
    for norm in sp.NORMS:
        v, v6 = ver[norm], ver[f"{norm} (6 sensors)"]
        rows[f"{norm}_verified"] = Measurement(
            v.passed and v6.passed, f"max Re eig {max(v.max_real_eig, v6.max_real_eig):.2f}, worst {norm} norm "
            f"{max(v.worst, v6.worst):.4e}", f"theta1-only and 6-sensor gains; {v.n_vertices} vertices + "
            f"{v.n_samples} samples")
    return Readout("\n".join(lines), rows)


def objective(obj: sp.ObjectiveStudy, D: sp.Designs) -> Readout:
    """Section 6: the six-sensor problems under p = 1, 2, inf and the theta1-only problems against them."""
    obj = validation.instance(obj, "obj", sp.ObjectiveStudy)
    D = validation.instance(D, "D", sp.Designs)
    lines = [f"p = {o[1:]:3s} {n:4s}: {d.status:18s} kappa "
             f"{np.array2string(d.kappa, formatter={'float_kind': lambda v: f'{v:.1f}'})}; used: "
             f"{', '.join(_used(d))}; kappa sin/cos th1 - 1 = {d.kappa[0] / d.kappa[1] - 1:+.1e}"
             for (o, n), d in obj.designs.items()]
    k = {key: d.kappa for key, d in obj.designs.items()}
    other_p = "; ".join(f"p = {o[1:]}: {'all six' if obj.all_used(o) else 'other'} sensors used" for o in ("l2", "linf"))
    both = ", ".join(n for n, u in zip(lpv.SENSOR_NAMES, D.all["h2"].used & D.all["hinf"].used) if u)
    rel = {n: abs(D.theta1[n].kappa[0] / D.all[n].kappa[0] - 1) for n in sp.NORMS}
    rows = {
        "objective": Measurement("p = 1"),
        "sensors": Measurement(obj.only_theta1, both, f"both theorems; used = beta_i > {obj.sparsity_tol:.0e} max beta "
                               f"(fixed before); {other_p}"),
        "sin_cos_equal": Measurement(
            obj.same_theta1("l1"), f"H2 {k[('l1', 'h2')][0]:.1f}/{k[('l1', 'h2')][1]:.1f}, "
            f"Hinf {k[('l1', 'hinf')][0]:.1f}/{k[('l1', 'hinf')][1]:.1f} (p = 1)",
            f"p = 2: H2 {k[('l2', 'h2')][0]:.0f}/{k[('l2', 'h2')][1]:.0f}, Hinf {k[('l2', 'hinf')][0]:.0f}/"
            f"{k[('l2', 'hinf')][1]:.0f} ({'equal' if obj.same_theta1('l2') else 'not equal'}); p = inf: six "
            f"{'equal' if obj.six_equal_linf else 'unequal'}, H2 {k[('linf', 'h2')][0]:.1f}, Hinf "
            f"{k[('linf', 'hinf')][0]:.1f} ({obj.designs[('linf', 'hinf')].status})"),
        "theta1_only": Measurement(max(rel.values()), f"rel. diff. H2 {rel['h2']:.0e}, Hinf {rel['hinf']:.0e}",
                                   "the comparison rows use the theta1-only problems"),
    }
    return Readout("\n".join(lines), rows)


def allowances(al: sp.Allowances, D: sp.Designs, bw: sp.BandwidthStudy, orbit: str = "2:1") -> Readout:
    """Section 7: Eq. 24 read both ways, against the paper's 0.1 and 0.08 deg (``orbit``: the p:q label)."""
    al = validation.instance(al, "al", sp.Allowances)
    D = validation.instance(D, "D", sp.Designs)
    bw = validation.instance(bw, "bw", sp.BandwidthStudy)
    validation.instance(orbit, "orbit", str)
    tu_min, kp, kb = al.minutes_per_tu, al.kappa_paper, al.kappa_band_hinf
    text = "\n".join([
        f"H2: {al.h2_deg:.4f} deg (intensity reading);  Hinf: {al.hinf_deg:.4f} deg",
        f"H2 per sample = 0.1 deg at dt = {al.dt_01:.4f} TU ({al.dt_01 * tu_min:.0f} min); H2 > Hinf per sample for "
        f"dt < {al.dt_eq:.4f} TU ({al.dt_eq * tu_min:.0f} min)",
        f"Eq. 8b literal (trace < gamma): H2 {al.h2_literal_deg:.3f} deg;  printed kappa = sqrt(beta/gamma): Hinf "
        f"{al.hinf_literal_deg:.4f} deg",
        f"kappa implied by Eq. 24 and the paper's 0.1 / 0.08 deg: H2 {kp['h2']:.0f}, Hinf {kp['hinf']:.0f}; "
        f"here H2 {al.kappa_h2:.0f}, Hinf {al.kappa_hinf:.0f}"])
    rows = {
        "h2_intensity": Measurement(al.h2_deg, f"{al.h2_deg:.4f} deg", f"{orbit} orbit; Section 9 tries other orbits "
                                    f"and disturbances; Eq. 8b read literally (trace < gamma) gives "
                                    f"{al.h2_literal_deg:.3f} deg, also outside"),
        "h2_per_sample": Measurement(float(D.theta1["h2"].noise_per_sample_deg(al.dt_01)[0]),
                                     f"0.1 deg at dt = {al.dt_01 * tu_min:.0f} min"),
        "hinf_noise": Measurement(al.hinf_deg, f"{al.hinf_deg:.4f} deg (R = {D.pole_radius:.0f}/TU; limit "
                                  f"{bw.limit_deg:.4f})", f"= asin(gamma / max r13) in the limit; max r13 = "
                                  f"{bw.r13_max:.3f} LU on the {orbit} orbit (Section 9 counts the resonances in the "
                                  "band)"),
        "ordering": Measurement(bool(al.h2_deg > al.hinf_deg), f"intensity reading: H2 {al.h2_deg:.3f} "
                                f"{'>' if al.h2_deg > al.hinf_deg else '<'} Hinf {al.hinf_deg:.3f}; per sample: H2 > "
                                f"Hinf iff dt < {al.dt_eq * tu_min:.0f} min"),
        "hinf_formula": Measurement("kappa = sqrt(beta)", note="with sqrt(beta) the verified Hinf norm stays just "
                                    "below gamma (Section 6 prints it); the "
                                    f"printed formula would give {al.hinf_literal_deg:.4f} deg, not 0.08"),
        "kappa_implied": Measurement(
            al.kappa_h2, f"H2 {al.kappa_h2:.0f}, Hinf {al.kappa_hinf:.0f}",
            f"not judged again (kappa = 1/sin of the allowance: the H2 allowance rows carry the comparison); H2 "
            f"{al.kappa_h2 / kp['h2']:.1f}x the implied value; Hinf "
            f"{'inside' if kb[0] < al.kappa_hinf <= kb[1] else 'outside'} the band ({kb[0]:.0f}, {kb[1]:.0f}] of the "
            "printed digits of 0.08 deg; the paper's Fig. 2 plots kappa but its text gives no value, so the implied "
            "ones are 1/sin(0.1 deg), 1/sin(0.08 deg)"),
    }
    return Readout(text, rows)


def _three_digits_km(x: float) -> str:
    return f"{float(f'{x:.3g}'):.0f}"


def trade_curve(tc: sp.TradeCurve, system: CR3BP = EARTH_MOON) -> Readout:
    """Section 8: the log-log slope of the required precision against gamma."""
    tc = validation.instance(tc, "tc", sp.TradeCurve)
    km = _km(system)
    return Readout(
        "log-log slope of kappa against gamma: " + ", ".join(f"{n} {s:.3f}" for n, s in tc.slope.items()),
        {"trade_curve": Measurement(tc.slope["h2"], f"slopes H2 {tc.slope['h2']:.2f}, Hinf {tc.slope['hinf']:.2f}",
                                    f"{tc.gammas.size} gammas from {_three_digits_km(tc.gammas[0] * km)} to "
                                    f"{_three_digits_km(tc.gammas[-1] * km)} km")})


def study_table(study: sp.SensitivityStudy, rd: sp.SensitivityReading) -> Readout:
    """Section 9: the per-orbit table of the sensitivity study (accelerations, reference level)."""
    study = validation.instance(study, "study", sp.SensitivityStudy)
    rd = validation.instance(rd, "rd", sp.SensitivityReading)
    h2i, hinf, j, tu_min = study.h2_intensity_deg, study.hinf_deg, rd.level_index, rd.minutes_per_tu
    lines = [f"{2 * study.h2_kappa.size} solves in {study.seconds:.0f} s; {rd.n_optimal} ended optimal",
             f"{'orbit':20s} {'max r13':>8s} {'Hinf deg':>9s} {'H2 int. deg (acc, lvl 1e-3)':>28s} "
             f"{'dt for H2 = 0.1 deg [min]':>26s} {'H2 > Hinf for dt < [min]':>25s}"]
    lines += [f"{nm:20s} {study.r13_max[i]:8.3f} {hinf[i, 0, j]:9.4f} {h2i[i, 0, j]:28.4f} "
              f"{rd.dt_01[i, 0, j] * tu_min:26.0f} {rd.dt_eq[i, 0, j] * tu_min:25.0f}" for i, nm in enumerate(rd.names)]
    return Readout("\n".join(lines))


def study_verdict(study: sp.SensitivityStudy, rd: sp.SensitivityReading) -> Readout:
    """Section 9: where both of the paper's numbers hold, and the four rows of the study."""
    study = validation.instance(study, "study", sp.SensitivityStudy)
    rd = validation.instance(rd, "rd", sp.SensitivityReading)
    tu_min, b = rd.minutes_per_tu, rd.r13_band
    lines = [f"{rd.hinf_in_band[:, 0, 0].sum()} of {len(rd.names)} orbits give Hinf in [0.075, 0.085) deg; "
             f"{len(rd.hits)} of {rd.all_hold.size} (orbit, structure, level) cases admit a sampling interval for the "
             "rest:"]
    lines += [f"  {h[0]:20s} {h[1]:13s} level {h[2]:<7g}: dt in [{h[3]:.0f}, {h[4]:.0f}) min" for h in rd.hits]
    lines += [f"dt for H2 = 0.1 deg per sample at level {lvl:g}: {np.nanmin(rd.dt_01[:, :, l_i]) * tu_min:.0f}-"
              f"{np.nanmax(rd.dt_01[:, :, l_i]) * tu_min:.0f} min over orbits and structures"
              for l_i, lvl in enumerate(study.levels)]
    dt_range = f"{np.nanmin(rd.dt_01) * tu_min:.0f}-{np.nanmax(rd.dt_01) * tu_min:.0f} min"
    rows = {
        "study": Measurement(rd.n_optimal, f"{len(rd.names)} orbits x {len(study.structures)} structures x "
                             f"{len(study.levels)} levels, {study.seconds:.0f} s, {rd.n_optimal}/"
                             f"{2 * study.h2_kappa.size} optimal", "theta1-only LMIs, Clarabel"),
        "where_hinf": Measurement(len(rd.orbits_in_band), f"{len(rd.orbits_in_band)} of {len(rd.names)} orbits: "
                                  f"{', '.join(rd.orbits_in_band) or 'none'}", f"band [0.075, 0.085) fixed before; "
                                  f"needs max r13 in [{b[0]:.3f}, {b[1]:.3f}] LU (unbounded-gain limit); disturbance "
                                  f"structure and level change it by at most {rd.hinf_spread:.0e} (relative)"),
        "where_h2": Measurement(rd.h2_intensity_in_band, f"{'in' if rd.h2_intensity_in_band else 'never in'} "
                                f"[0.05, 0.15) deg as an intensity (max {rd.h2_intensity_max:.3f} deg); per sample at "
                                f"dt = {dt_range}", "band [0.05, 0.15) fixed before; range over orbits, structures and "
                                "levels; the per-sample reading needs a sampling interval, which the paper does not "
                                "state"),
        "both": Measurement(len(rd.hits), f"{len(rd.hits)} of {rd.all_hold.size} cases, e.g. " + (
            f"{rd.hits[0][0]}, dt {rd.hits[0][3]:.0f}-{rd.hits[0][4]:.0f} min" if rd.hits else "none"),
            f"only with the per-sample reading of H2, on an orbit with max r13 in [{b[0]:.2f}, {b[1]:.2f}] LU, for the "
            "dt windows listed"),
    }
    return Readout("\n".join(lines), rows)


# =============================================================================================== notebook 12
def observer_gains(od: obs.ObserverDesigns, gamma: float) -> Readout:
    """Section 1: both gains, their solve status and verification."""
    od = validation.instance(od, "od", obs.ObserverDesigns)
    gamma = validation.positive(gamma, "gamma")
    lines, rows = [], {}
    for n, d in od.designs.items():
        v = od.verification[n]
        lines.append(f"{n:4s}: {d.status}; kappa {d.kappa[:2].round(1)}, Eq. 24 noise {d.noise_deg[0]:.4f} deg, "
                     f"|L| = {d.gain_norm:.1f}; verified: max Re eig {v.max_real_eig:.2f}, worst {n} {v.worst:.3e} < "
                     f"{gamma}: {v.passed}")
        rows[f"{n}_gain"] = Measurement(
            bool(v.passed and d.optimal), f"{d.status}, |L| = {d.gain_norm:.0f}, worst {n} norm {v.worst:.2e}",
            "Hinf with bandwidth bound R = 1000/TU" if n == "hinf" else "no gain bound")
    return Readout("\n".join(lines), rows)


def allowance_at_dt(al: obs.AllowanceAtDt, sigma_deg: float, system: CR3BP = EARTH_MOON) -> Readout:
    """Section 2: what the simulated noise ``sigma_deg`` is against each allowance at the simulated interval."""
    al = validation.instance(al, "al", obs.AllowanceAtDt)
    sigma_deg = validation.positive(sigma_deg, "sigma_deg")
    tu_min, h2_ps, hinf_n = _minutes(system), al.h2_per_sample_deg, al.hinf_deg
    text = (f"dt = {al.dt} TU ({al.dt * tu_min:.1f} min): H2 allows {h2_ps:.3f} deg per sample (intensity reading "
            f"{al.h2_intensity_deg:.4f} deg); Hinf allows {hinf_n:.4f} deg RMS\n"
            f"the simulated {sigma_deg} deg is {sigma_deg / h2_ps:.2f}x the H2 and {sigma_deg / hinf_n:.2f}x the Hinf "
            "allowance")
    above = h2_ps > hinf_n
    row = Measurement(
        h2_ps, f"H2 {h2_ps:.2f} deg per sample > Hinf {hinf_n:.3f} deg" if above else
        f"H2 {h2_ps:.3f} < Hinf {hinf_n:.3f} deg",
        f"per-sample reading at dt = {al.dt * tu_min:.1f} min (our choice), outside notebook 11's window where both "
        f"numbers hold; H2 = 0.1 deg per sample at dt = {al.dt_01 * tu_min:.0f} min (Section 6 simulates it); as an "
        f"intensity H2 allows {al.h2_intensity_deg:.3f} deg < Hinf (notebook 11)",
        f"only the ordering agrees; H2 allows {h2_ps:.2f} deg per sample, {h2_ps / 0.1:.1f}x the paper's 0.1 deg"
        if above else "reversed")
    return Readout(text, {"ordering_dt": row})


def measurements(sim: obs.Fig3Runs, sc: Scenario) -> Readout:
    """Section 3: samples, where rho comes from the estimate, the initial error and the lag a held measurement
    would cause."""
    sim = validation.instance(sim, "sim", obs.Fig3Runs)
    sc = validation.instance(sc, "sc", Scenario)
    m, km, tu_min = sc.model, _km(sc.model.system), _minutes(sc.model.system)
    frac = sim.runs["h2"].rho_from_estimate.mean()
    th1_rate = np.abs(np.gradient(np.unwrap(m.angles(sim.truth)[0]), sim.t))  # rad/TU
    return Readout(
        f"{sim.t.size} measurements; rho taken from the estimate on {100 * frac:.1f} % of them (|sin th3| < 0.04)\n"
        f"initial position error {sim.initial_error * km:.0f} km ({abs(sim.x_hat0[0] - sim.truth[0, 0]) * km:.0f} km "
        "per axis)\n"
        f"lag |dtheta1/dt| DT if the whole measurement were held: up to {np.degrees(th1_rate.max() * sim.dt):.2f} deg "
        f"at DT = {sim.dt * tu_min:.1f} min")


def convergence(cv: obs.Convergence, sim: obs.Fig3Runs, system: CR3BP = EARTH_MOON) -> Readout:
    """Section 4: the guaranteed RMS of each design against the simulated runs."""
    cv = validation.instance(cv, "cv", obs.Convergence)
    sim = validation.instance(sim, "sim", obs.Fig3Runs)
    km, span = _km(system), sim.period
    return Readout("\n".join(
        f"{n:4s}: guaranteed RMS {cv.bound[n] * km:7.1f} km; first below at {cv.first[n]:.3f} TU "
        f"({cv.first[n] / span * 100:.1f} % of the period); RMS after {cv.rms[n] * km:7.1f} km; "
        f"with exact rho (diagnostic) {cv.rms_exact[n] * km:7.1f} km" for n in cv.bound))


def convergence_time(cv: obs.Convergence, sim: obs.Fig3Runs, system: CR3BP = EARTH_MOON) -> Readout:
    """Section 4: the convergence time predicted by the slowest pole, the noise-free run and the initial-error
    sweep."""
    cv = validation.instance(cv, "cv", obs.Convergence)
    sim = validation.instance(sim, "sim", obs.Fig3Runs)
    km, span, e0 = _km(system), sim.period, sim.initial_error
    lines = [f"{n:4s}: slowest closed-loop decay on the orbit {cv.decay[n]:.2f}/TU; predicted time from {e0 * km:.0f} "
             f"km to the paper's level {cv.level[n] * km:.0f} km: {cv.t_pred[n]:.2f} TU "
             f"({100 * cv.t_pred[n] / span:.1f} % of the period)" for n in cv.decay]
    lines.append(f"h2 , no noise, exact rho: first below the level at {cv.first_clean:.3f} TU "
                 f"({100 * cv.first_clean / span:.1f} % of the period)")
    lines += [f"h2 , initial error {f_ * e0 * km:7.0f} km: first below the level at {tf:.3f} TU "
              f"({100 * tf / span:.1f} % of the period); RMS over 5-10 % of the period {er * km:6.0f} km"
              for f_, tf, er in zip(cv.e0_scales, cv.first_sweep, cv.early_sweep)]
    return Readout("\n".join(lines))


def line_crossings(lc: obs.LineCrossings, sim: obs.Fig3Runs, system: CR3BP = EARTH_MOON) -> Readout:
    """Section 5: the Earth-Moon line crossings and the running RMS near them and elsewhere."""
    lc = validation.instance(lc, "lc", obs.LineCrossings)
    sim = validation.instance(sim, "sim", obs.Fig3Runs)
    km = _km(system)
    lines = ["Earth-Moon line crossed (rho from the estimate) from t = " + ", ".join(f"{t0:.2f}" for t0 in lc.starts)
             + " TU"]
    for n in sim.runs:
        at_line = lc.running_rms[n][lc.near & sim.settled]
        lines.append(f"{n:4s}: after 10 % of the run, running RMS within 0.1 TU of a crossing up to "
                     f"{at_line.max() * km if at_line.size else np.nan:6.0f} km; median elsewhere "
                     f"{np.median(lc.running_rms[n][~lc.near & sim.settled]) * km:5.0f} km")
    return Readout("\n".join(lines))


def converges(cv: obs.Convergence, sim: obs.Fig3Runs, system: CR3BP = EARTH_MOON,
              acc: obs.Fig3Accuracy | None = None) -> Readout:
    """Section 6: the two rows of Fig. 3's claim "converge rapidly and stay accurate", judged by ``acc`` (a
    :class:`observer_simulation.Fig3Accuracy` over the chapter's intervals; default: ``sim``'s interval alone),
    with the convergence time the slowest pole predicts, the initial-error sweep and the LMI guarantee of ``cv``
    (Section 4) as context."""
    cv = validation.instance(cv, "cv", obs.Convergence)
    sim = validation.instance(sim, "sim", obs.Fig3Runs)
    km, span, e0, tu_min = _km(system), sim.period, sim.initial_error, _minutes(system)
    if acc is None:
        label = f"{sim.dt * tu_min:.1f} min"
        acc = obs.Fig3Accuracy.measure({label: (sim.t, {n: sim.runs[n].position_error for n in cv.level})}, cv.level,
                                       span, reference={label: (sim.t, {n: sim.exact[n].position_error
                                                                        for n in cv.level})})
    acc = validation.instance(acc, "acc", obs.Fig3Accuracy)
    at = f"{sim.dt * tu_min:.1f} min"
    rows = {}
    for n in ("h2", "hinf"):
        note = (f"prediction from the slowest closed-loop pole ({cv.decay[n]:.1f}/TU) at {at}: from {e0 * km:,.0f} km "
                f"to {cv.level[n] * km:.0f} km in {cv.t_pred[n]:.2f} TU ({100 * cv.t_pred[n] / span:.1f} % of the "
                "period)")
        ok = cv.e0_max_ok(e0 * km, span)
        if n == "h2":
            note += (f"; no noise, exact rho {100 * cv.first_clean / span:.1f} %; initial-error sweep at {at}: "
                     f"{cv.e0_scales[0] * e0 * km:.0f}-{e0 * km:,.0f} km (Section 4)")
        note += (f"; the LMI guarantee at {at} ({cv.bound[n] * km:.0f} km, assumes exact rho) is a diagnostic "
                 f"(Section 4: RMS on the true rho {cv.rms_exact[n] * km:.0f} km)")
        why = acc.why(n, km)
        if why:  # where the claim holds: the intervals and schedulings at which the observer is accurate, the starts
            labels = [lab for lab, m in acc.rms if m == n]
            good = [lab for lab in labels if acc.accurate(lab, n)]
            good_ref = [lab for lab in labels if acc.reference_rms.get((lab, n), np.inf) <= acc.level[n]]
            why += ("; where it holds: accurate with rho triangulated at " + (", ".join(good) or "neither interval")
                    + "; on the true rho (the LMIs' assumption) at " + (", ".join(good_ref) or "neither interval"))
            if n == "h2":
                why += (f"; settles within 5 % at {at} from starts up to {ok:,.0f} km (the paper states no start)"
                        if np.isfinite(ok) else f"; settles within 5 % at {at} from none of the swept starts")
        rows[f"{n}_converges"] = Measurement(acc.holds(n), acc.shown(n, km), note, why)
    return Readout("", rows)


def comparison(sim: obs.Fig3Runs, ww: obs.WindowRerun, od: obs.ObserverDesigns, al: obs.AllowanceAtDt,
               sigma_deg: float, system: CR3BP = EARTH_MOON) -> Readout:
    """Section 6: both observers at the sampling interval where H2 allows 0.1 deg per sample, and the remaining
    rows of the chapter."""
    sim = validation.instance(sim, "sim", obs.Fig3Runs)
    ww = validation.instance(ww, "ww", obs.WindowRerun)
    od = validation.instance(od, "od", obs.ObserverDesigns)
    al = validation.instance(al, "al", obs.AllowanceAtDt)
    validation.positive(sigma_deg, "sigma_deg")
    km, tu_min, des = _km(system), _minutes(system), od.designs
    med, med_w = {n: sim.median_settled(n) for n in sim.runs}, ww.median
    h2_w = des["h2"].noise_per_sample_deg(ww.dt)[0]
    text = (f"dt = {ww.dt:.4f} TU ({ww.dt * tu_min:.0f} min), {ww.n} samples: H2 allows {h2_w:.3f} deg per sample, "
            f"Hinf {al.hinf_deg:.4f} deg; median error after 10 % of the run: H2 {med_w['h2'] * km:.0f} km, Hinf "
            f"{med_w['hinf'] * km:.0f} km")
    frac = sim.runs["h2"].rho_from_estimate.mean()
    ekf_rms = float(np.sqrt(np.mean(sim.runs["ekf"].position_error[sim.settled] ** 2)))
    rows = {
        "hinf_larger": Measurement(
            bool(med["hinf"] > med["h2"] and med_w["hinf"] > med_w["h2"]),
            f"median {med['hinf'] * km:.0f} vs {med['h2'] * km:.0f} km at dt = {sim.dt * tu_min:.1f} min; "
            f"{med_w['hinf'] * km:.0f} vs {med_w['h2'] * km:.0f} km at dt = {ww.dt * tu_min:.0f} min",
            f"{sigma_deg} deg noise is {sigma_deg / al.h2_per_sample_deg:.2f}x (dt {sim.dt * tu_min:.1f} min) and "
            f"{sigma_deg / h2_w:.2f}x (dt {ww.dt * tu_min:.0f} min) the H2 and {sigma_deg / al.hinf_deg:.2f}x the Hinf "
            "allowance"),
        "rho_from_estimate": Measurement(frac, f"{100 * frac:.1f} % of samples", "threshold 0.04 taken from the paper; "
                                         "triangulation singular near the Earth-Moon line"),
        "ekf": Measurement(ekf_rms, f"RMS {ekf_rms * km:.0f} km after 10 % of the run",
                           "continuous-discrete EKF, sigma_acc = 1e-3 LU/TU^2"),
        "dt": Measurement(sim.dt, f"{sim.dt} TU ({sim.dt * tu_min:.1f} min)"),
    }
    return Readout(text, rows)


def scheduling_error(se: rb.SchedulingError, system: CR3BP = EARTH_MOON) -> Readout:
    """Section 6: what the triangulation error does to the scheduling parameters and to the error dynamics."""
    se = validation.instance(se, "se", rb.SchedulingError)
    km = _km(system)
    acc = km / check_system(system, "system").time_unit_s**2
    rel = ", ".join(f"{n} {100 * v:.1f} %" for n, v in zip(lpv.RHO_NAMES, se.rho_rel_rms))
    return Readout(
        f"{se.sigma_deg} deg on each angle, {se.n_draws} draws per orbit sample; triangulated on "
        f"{100 * se.triangulated:.1f} % of them\n"
        f"RMS relative error of the triangulated rho: {rel}\n"
        f"gravity error |delta_f|: RMS {se.s_f:.3f} LU/TU^2 ({se.s_f * acc:.1e} km/s^2) = {se.s_f / 1e-3:.0f}x the "
        f"assumed disturbance S_d = 1e-3 LU/TU^2\n"
        f"theta1-channel error |delta_y|: RMS {se.s_y:.4f} = {se.s_y / np.radians(se.sigma_deg):.1f}x the angle noise\n"
        f"widened box ({100 * se.coverage:g} % of the triangulated rho per parameter; {100 * se.inside:.1f} % of "
        "them inside on all six):\n" + "\n".join(
            f"  rho {n:8s}: [{lo:9.4f}, {hi:9.4f}]" for n, lo, hi in zip(lpv.RHO_NAMES, se.box.lower, se.box.upper)))


def robust_designs(rd: rb.RobustDesigns, system: CR3BP = EARTH_MOON) -> Readout:
    """Section 6: the robust designs, their least bound for the sensor and the guarantee."""
    rd = validation.instance(rd, "rd", rb.RobustDesigns)
    km, tu_min = _km(system), _minutes(system)
    lines = [f"sensor: {rd.sigma_deg} deg per sample every {rd.dt * tu_min:.0f} min"]
    for n, d in rd.designs.items():
        v = rd.verification[n]
        lines.append(f"{n:4s}: least gamma* = {rd.gamma_star[n]:.5f} LU ({rd.gamma_star[n] * km:.0f} km) for kappa "
                     f"{rd.kappa_sensor[n]:.0f}; guarantee sqrt(3) gamma* = {rd.guarantee[n] * km:.0f} km; "
                     f"|L| = {d.gain_norm:.0f}; {d.status}; verified on the widened box ({v.n_vertices} vertices + "
                     f"{v.n_samples} samples): worst {n} norm {v.worst:.2e} < gamma*: {v.passed}")
    return Readout("\n".join(lines))


def window(ws: rb.WindowStudy, rd: rb.RobustDesigns, od: obs.ObserverDesigns,
           system: CR3BP = EARTH_MOON) -> Readout:
    """Section 6: Fig. 3 at the 233-min interval against every guarantee; the rows on Fig. 3's accuracy, the robust
    designs and the small start (the range-free claim is measured by :class:`observer_simulation.RangeFree`)."""
    ws = validation.instance(ws, "ws", rb.WindowStudy)
    rd = validation.instance(rd, "rd", rb.RobustDesigns)
    od = validation.instance(od, "od", obs.ObserverDesigns)
    km, tu_min = _km(system), _minutes(system)
    lines = [f"dt = {ws.dt * tu_min:.0f} min, {ws.t.size} samples; initial error {ws.e0['large'] * km:.0f} km (large), "
             f"{ws.e0['small'] * km:.0f} km (small); rho in the widened box on {100 * ws.inside:.1f} % of samples",
             f"{'run':28s} {'start':6s} {'RMS after 10 % [km]':>20s} {'guarantee [km]':>15s}  within"]
    for (design, n, start), _ in ws.errors.items():
        g = ws.guarantee[(design.split(",")[0], n)]
        lines.append(f"{design + ' ' + n:28s} {start:6s} {ws.rms(design, n, start) * km:20.0f} {g * km:15.0f}  "
                     f"{ws.holds(design, n, start)}")
    lines.append("robust bound from the inputs realised in this run: " + ", ".join(
        f"{n} {b * km:.0f} km" for n, b in ws.posterior.items()))
    follow = {(d, s_): ws.fix_following(d, "hinf", s_) for d in ("nominal", "robust") for s_ in ("large", "small")}
    g_hinf = ws.guarantee[("nominal", "hinf")]
    resid = {k: ws.fix_residual(k[0], "hinf", k[1]) for k in follow}
    resid0 = {k: ws.fix_residual(k[0], "hinf", k[1], lag=0) for k in follow}
    fix_rms = float(np.sqrt(np.nanmean(ws.fix_error[ws.settled] ** 2)))
    gain_dt = {d: float(np.linalg.norm(g.designs["hinf"].gain(), 2) * ws.dt) for d, g in (("nominal", od), ("robust", rd))}
    lines.append(f"angle-only fixes: RMS {fix_rms * km:.0f} km; Hinf runs against the fix of the sample before "
                 "(correlation, RMS ratio): " + ", ".join(f"{d} {s_} {c:.2f}, {r:.2f}" for (d, s_), (c, r)
                                                          in follow.items()))
    lines.append("Hinf error minus the fix error of the sample before, RMS of the vector difference: " + ", ".join(
        f"{d} {s_} {resid[(d, s_)] * km:.0f} km" for d, s_ in follow) + f" (nominal Hinf guarantee {g_hinf * km:.0f} "
        "km); minus the fix of the same sample: " + ", ".join(f"{resid0[k] * km:.0f}" for k in follow) + " km")
    starts = ("large", "small")

    def within(design, starts_=starts):
        return all(ws.holds(design, n, s_) for n in ("h2", "hinf") for s_ in starts_)

    def shown(design, start="large"):
        return "; ".join(f"{n}: {ws.rms(design, n, start) * km:.0f} km vs {ws.guarantee[(design.split(',')[0], n)] * km:.0f}"
                         " km" for n in ("h2", "hinf"))

    rows = {
        "fig3_233": Measurement(
            within("nominal", ("large",)),
            shown("nominal") + (": within the guarantee" if within("nominal", ("large",)) else ": above the guarantee"),
            f"RMS after 10 % of the run from the large start against the nominal guarantee, which assumes exact rho "
            f"(the next row: on the true rho); dt = {ws.dt * tu_min:.0f} min; the paper's accuracy claim is judged "
            "in the H2 / Hinf rows against its own level"),
        "fig3_233_exact": Measurement(within("nominal, exact rho"), shown("nominal, exact rho") + " (large start); "
                                      + shown("nominal, exact rho", "small") + " (small start)"),
        "robust": Measurement(
            within("robust") and all(v.passed for v in rd.verification.values()),
            shown("robust") + " (large start); " + shown("robust", "small") + " (small start)",
            f"least gamma* H2 {rd.gamma_star['h2'] * km:.0f}, Hinf {rd.gamma_star['hinf'] * km:.0f} km for 0.1 deg at "
            f"{ws.dt * tu_min:.0f} min (nominal LMIs: H2 {ws.guarantee[('nominal', 'h2')] * km:.0f}, Hinf "
            f"{ws.guarantee[('nominal', 'hinf')] * km:.0f} km); realised-input bound H2 {ws.posterior['h2'] * km:.0f} "
            f"km; rho in the widened box on {100 * ws.inside:.1f} % of samples; robust solves ended "
            + ", ".join(f"{n} {d.status}" for n, d in rd.designs.items())
            + " (the gains are judged by their verification, not by the solver's status)"),
        "small_e0": Measurement(
            within("nominal", ("small",)),
            shown("nominal", "small") + (": within the guarantee" if within("nominal", ("small",)) else
                                         ": above the guarantee from the small start too"),
            f"start {ws.e0['small'] * km:.0f} km instead of {ws.e0['large'] * km:.0f} km; dt = {ws.dt * tu_min:.0f} "
            "min; " + ("the large start's transient explains the fig3_233 shortfall" if within("nominal", ("small",))
                       else "so the scheduling error, not the transient, explains the fig3_233 shortfall")),
        "hinf_follows_fix": Measurement(
            max(resid.values()) / g_hinf,
            f"RMS |e(k+1) - f(k)| / nominal Hinf guarantee {max(resid.values()) / g_hinf:.2f} (largest of four runs: "
            + ", ".join(f"{r * km:.0f}" for r in resid.values()) + f" km against {g_hinf * km:.0f} km); against the "
            f"same sample's fix {min(resid0.values()) / g_hinf:.1f}x",
            f"e(k+1): the Hinf error vector at sample k+1, f(k): the error vector of the angle-only fix of sample k; "
            f"nominal and robust Hinf, large and small start; fix RMS {fix_rms * km:.0f} km; lag-1 correlation of the "
            "error norms " + ", ".join(f"{c:.2f}" for c, _ in follow.values()) + f"; ||L|| dt = "
            f"{gain_dt['nominal']:.0f} (nominal), {gain_dt['robust']:.0f} (robust): the estimate is pulled onto the "
            "held angles' fix within one interval, so both Hinf gains show the same RMS from both starts",
            "what separates the Hinf error from the previous angle-only fix is larger than the observer's own "
            "guaranteed error: the Hinf error is not only the previous fix's error"),
    }
    return Readout("\n".join(lines), rows)


r"""Reference orbits and observer sites of the maneuver-detection paper (Greaves & Scheeres 2021, "Dynamics" and
"Measurements"), as studies that return frozen results (chapter 01).

* :func:`variational_check`: the STM and second-order STT of the CR3BP against central finite differences over one
  period of an orbit (error against step: an :math:`h^2` truncation branch and an :math:`\varepsilon/h` round-off
  branch);
* :func:`halo_family_study`: the southern L2 halo family through the 9:2 NRHO, its stability index
  :math:`\nu = (|\lambda_{max}| + 1/|\lambda_{max}|)/2` and the two stable-NRHO candidates (the inner band's
  edge, :func:`cislunar.cr3bp.orbits.stable_nrho`, and the outer band's most stable member,
  :func:`cislunar.cr3bp.orbits.stable_nrho_outer`);
* :func:`observer_visibility`, :func:`station_pair_sweep`, :func:`perilune_visibility`: what the paper's observers
  (an observer at rest at L2, a DRO observer and three lunar-surface stations, :mod:`cislunar.sensing.sites`) see;
* figure functions for the chapter (``figure_*``), each returning a Matplotlib figure.

Units: positions in km (Moon-centred where stated), times in days or hours as named, states non-dimensional
(rotating frame, LU and LU/TU).
"""

from __future__ import annotations

from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np

from cislunar.cr3bp import orbits, propagation
from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.orbits import PeriodicOrbit
from cislunar.publish import plotting
from cislunar.sensing import sites
from cislunar.utils import validation

__all__ = [
    "HaloFamilyStudy",
    "OrbitVisibility",
    "PeriluneVisibility",
    "StationSweep",
    "VariationalCheck",
    "figure_dro_family",
    "figure_halo_stability",
    "figure_nrho_family",
    "figure_observer_sites",
    "figure_variational_check",
    "halo_family_study",
    "line_of_sight_samples",
    "observer_visibility",
    "perilune_visibility",
    "station_pair_sweep",
    "variational_check",
    "visibility_report",
]


# ---------------------------------------------------------------------------------------------------------------
# STM and STT against finite differences
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class VariationalCheck:
    """Largest relative error of the STM and the STT at one period against central differences, per step.

    Attributes
    ----------
    steps : ndarray, shape (n,)
        Finite-difference steps (LU for positions, LU/TU for velocities).
    stm_error, stt_error : ndarray, shape (n,)
        ``max|FD - exact| / max|exact|`` for the STM (differences of the state) and the STT (differences of the
        STM), dimensionless.
    """

    steps: np.ndarray
    stm_error: np.ndarray
    stt_error: np.ndarray

    @property
    def best_stm(self) -> float:
        """Smallest STM error over the steps (the bottom of the V)."""
        return float(np.min(self.stm_error))

    @property
    def best_stt(self) -> float:
        """Smallest STT error over the steps."""
        return float(np.min(self.stt_error))


def variational_check(system: CR3BP, orbit: PeriodicOrbit, n_steps: int, *, log10_range=(-9.0, -2.5)
                      ) -> VariationalCheck:
    """Compare heyoka's STM and STT over one period of ``orbit`` with central differences at ``n_steps`` steps
    spaced logarithmically over ``10**log10_range``."""
    check_system(system)
    validation.instance(orbit, "orbit", PeriodicOrbit, "a cislunar.cr3bp.orbits.PeriodicOrbit")
    n_steps = validation.integer(n_steps, "n_steps", minimum=2)
    lo, hi = (float(v) for v in validation.as_array(log10_range, "log10_range", shape=(2,)))
    exact = propagation.propagate_stt(system, orbit.x0, orbit.period)
    steps = np.logspace(lo, hi, n_steps)
    stm_err, stt_err = [], []
    for h in steps:
        fd1 = propagation.stm_finite_difference(system, orbit.x0, orbit.period, h)
        fd2 = propagation.stt_finite_difference(system, orbit.x0, orbit.period, h)
        stm_err.append(np.max(np.abs(fd1 - exact.stm[-1])) / np.max(np.abs(exact.stm[-1])))
        stt_err.append(np.max(np.abs(fd2 - exact.stt[-1])) / np.max(np.abs(exact.stt[-1])))
    return VariationalCheck(steps, np.array(stm_err), np.array(stt_err))


def figure_variational_check(check: VariationalCheck):
    """Error against step for the STM and STT, with the :math:`h^2` and :math:`1/h` guides."""
    validation.instance(check, "check", VariationalCheck, "a VariationalCheck (variational_check)")
    steps, stm_err, stt_err = check.steps, check.stm_error, check.stt_error
    fig, ax = plt.subplots()
    ax.loglog(steps, stm_err, "o-", label="STM  (central differences of the state)")
    ax.loglog(steps, stt_err, "s-", label="STT  (central differences of the STM)")
    ax.loglog(steps, stm_err[-1] * (steps / steps[-1]) ** 2, "k:", lw=1, label=r"$\propto h^2$ (truncation)")
    ax.loglog(steps, stm_err[0] * steps[0] / steps, "k--", lw=1, label=r"$\propto 1/h$ (round-off)")
    ax.set_ylim(min(stm_err) / 10, 10 * max(stt_err))
    ax.set_xlabel("finite-difference step h [LU, LU/TU]")
    ax.set_ylabel("max relative error vs heyoka [-]")
    ax.set_title("Variational equations vs finite differences, one 9:2 NRHO period")
    ax.legend()
    return fig


# ---------------------------------------------------------------------------------------------------------------
# DRO figure (Wolf & Jones orbits passed in as plain orbits and labels)
# ---------------------------------------------------------------------------------------------------------------
def _check_groups(groups) -> list:
    """A non-empty sequence of (PeriodicOrbit, str) pairs, one of whose labels mentions ``observer_t0``."""
    what = "a sequence of (PeriodicOrbit, label) pairs"
    if isinstance(groups, (str, bytes, dict)) or not hasattr(groups, "__iter__"):
        raise validation.ArgumentTypeError(f"groups must be {what}; got {type(groups).__name__}")
    out = []
    for i, item in enumerate(groups):
        if not isinstance(item, (tuple, list)) or len(item) != 2:
            raise validation.ArgumentTypeError(f"groups[{i}] must be a (PeriodicOrbit, label) pair; got "
                                               f"{type(item).__name__}")
        validation.instance(item[0], f"groups[{i}] orbit", PeriodicOrbit, "a cislunar.cr3bp.orbits.PeriodicOrbit")
        validation.instance(item[1], f"groups[{i}] label", str)
        out.append((item[0], item[1]))
    if not out:
        raise ValueError(f"groups must be {what}; got an empty sequence")
    if not any("observer_t0" in label for _, label in out):
        raise ValueError("groups must hold an orbit whose label mentions 'observer_t0' (its period sets the span "
                         "of the printed state)")
    return out


def figure_dro_family(system: CR3BP, family, zoom_family, groups, printed_state):
    """The DRO family, a zoom on the -x crossing of the given DROs and their periods against that crossing.

    Parameters
    ----------
    family, zoom_family : sequence of PeriodicOrbit
        The whole family (drawn in grey) and members across the zoom window (the period curve).
    groups : sequence of (PeriodicOrbit, str)
        Each distinct highlighted orbit (periodic) with its legend label, sorted by crossing.
    printed_state : array, shape (6,)
        A non-periodic state propagated for one period of the first orbit whose label mentions it (dashed).
    """
    check_system(system)
    family = validation.sequence_of(family, "family", PeriodicOrbit, "PeriodicOrbit")
    zoom_family = validation.sequence_of(zoom_family, "zoom_family", PeriodicOrbit, "PeriodicOrbit")
    groups = _check_groups(groups)
    printed_state = validation.as_state(printed_state, "printed_state", batch=False)
    em = system
    colours = [plt.cm.tab10(i) for i in (0, 1, 2, 4, 5, 6, 8, 9)[:len(groups)]]  # no red (printed observer)
    x_moon = em.secondary_position[0]
    cross = np.array([(o.x0[0] - x_moon) * em.length_unit_km for o, _ in groups])
    period = np.array([o.period_days for o, _ in groups])
    fig = plt.figure(figsize=(14, 6.2))
    grid = fig.add_gridspec(1, 3, width_ratios=[0.62, 1, 1])
    ax1, axz, ax2 = (fig.add_subplot(grid[0, k]) for k in range(3))
    for orb in family[:: max(1, len(family) // 12)]:
        plotting.plot_rotating(ax1, orb.sample(400)[1], em, "xy", units="km", moon_centred=True, color="0.75",
                               lw=0.8)
    ax1.plot([], [], color="0.75", lw=0.8, label="DRO family")
    for (orb, label), col in zip(groups, colours):
        xs = orb.sample(2000)[1]
        plotting.plot_rotating(ax1, xs, em, "xy", units="km", moon_centred=True, color=col, lw=1.2)
        plotting.plot_rotating(axz, xs, em, "xy", units="km", moon_centred=True, color=col, lw=1.5, label=label)
    obs_period = next(o.period for o, label in groups if "observer_t0" in label)
    bad = propagation.propagate(em, printed_state, np.linspace(0, obs_period, 400)).x
    plotting.plot_rotating(ax1, bad, em, "xy", units="km", moon_centred=True, color="C1", ls="--",
                           label="observer state as printed (not periodic)")
    plotting.plot_primaries(ax1, em, "xy", moon_centred=True, units="km", earth=False)
    ax1.set_aspect("equal", adjustable="box")
    ax1.set_title("DRO family (grey) and\nWolf & Jones orbits (colour)", fontsize=10)
    plotting.thousands_km_axes(ax1, "xy", nbins=4)
    plotting.thousands_km_axes(axz, "xy")
    axz.set_xlim(cross.min() - 1500.0, cross.max() + 1500.0)
    axz.set_ylim(-15000.0, 15000.0)
    axz.set_aspect("auto")
    axz.set_title("zoom: where the W&J DROs cross the x axis", fontsize=10)
    ax2.plot([(o.x0[0] - x_moon) * em.length_unit_km for o in zoom_family], [o.period_days for o in zoom_family],
             "-", color="0.6", lw=1, zorder=1)
    for x, p, col in zip(cross, period, colours):
        ax2.plot(x, p, "o", color=col, ms=7, mec="k", mew=0.5, zorder=3)
    ax2.set_xlim(axz.get_xlim())
    ax2.set_ylim(period.min() - 0.25 * np.ptp(period), period.max() + 0.25 * np.ptp(period))
    ax2.xaxis.set_major_formatter(plt.FuncFormatter(lambda v, _: f"{v / 1e3:g}"))
    for ax in (axz, ax2):  # one tick per 10^3 km in both panels, so that crossings and markers line up by eye
        ax.xaxis.set_major_locator(plt.MultipleLocator(1000.0))
    ax2.set_xlabel("x-axis crossing (Moon-centred) [10³ km]")
    ax2.set_ylabel("period [days]")
    ax2.set_title("period of each W&J DRO (same x scale as the zoom)", fontsize=10)
    ins = ax2.inset_axes([0.58, 0.55, 0.39, 0.40])
    ins.plot([(o.x0[0] - x_moon) * em.length_unit_km / 1e3 for o in family], [o.period_days for o in family], "-",
             color="0.4", lw=1)
    ins.add_patch(plt.Rectangle((ax2.get_xlim()[0] / 1e3, period.min() - 0.6), np.ptp(ax2.get_xlim()) / 1e3,
                                np.ptp(period) + 1.2, fill=False, ec="k", lw=0.8))
    ins.set_xlabel("crossing [10³ km]", fontsize=7, labelpad=1)
    ins.set_ylabel("period [d]", fontsize=7, labelpad=1)
    ins.tick_params(labelsize=7)
    ins.set_title("whole family (box: this panel)", fontsize=7, pad=2)
    ins.grid(False)
    handles, labels = [], []
    for ax in (ax1, axz):
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.append(h)
            labels.append(lab)
    fig.legend(handles, labels, loc="lower center", ncol=4, frameon=False, fontsize=8)
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    return fig


# ---------------------------------------------------------------------------------------------------------------
# The southern L2 halo family and the NRHOs
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class HaloFamilyStudy:
    """The southern L2 halo family with the 9:2 NRHO and both stable candidates.

    Attributes
    ----------
    nrho, stable, outer : PeriodicOrbit
        The 9:2 NRHO, the inner stable band's edge (stability index 1) and the outer band's most stable member.
    family : tuple of PeriodicOrbit
        Members by pseudo-arclength continuation.
    step : float
        Continuation step.
    """

    nrho: PeriodicOrbit
    stable: PeriodicOrbit
    outer: PeriodicOrbit
    family: tuple
    step: float

    @property
    def perilune_km(self) -> np.ndarray:
        return np.array([o.perilune_radius_km for o in self.family])

    @property
    def stability_index(self) -> np.ndarray:
        return np.array([o.stability_index for o in self.family])

    @property
    def broucke_margin(self) -> np.ndarray:
        """``max|Re nu_B| - 1`` of each member's Broucke indices (< 0: linearly stable)."""
        return np.array([np.max(np.abs(o.broucke_indices.real)) - 1.0 for o in self.family])

    @property
    def outer_band(self) -> tuple:
        """Linearly stable members farther from the Moon than the 9:2 NRHO."""
        return tuple(o for o, m in zip(self.family, self.broucke_margin)
                     if m < 0 and o.perilune_radius_km > self.nrho.perilune_radius_km)

    @property
    def band_perilune_km(self) -> tuple:
        """(smallest, largest) perilune radius of the outer band's members, km."""
        rp = [o.perilune_radius_km for o in self.outer_band]
        return min(rp), max(rp)

    def report(self) -> str:
        """The printed summary of the three orbits and of the outer band."""
        lines = []
        for name, o in (("9:2 NRHO", self.nrho), ("stable NRHO", self.stable), ("outer band", self.outer)):
            lines.append(f"{name:12s} x0 = [{o.x0[0]:.10f}, 0, {o.x0[2]:+.10f}, 0, {o.x0[4]:+.10f}, 0]  "
                         f"T = {o.period_days:.6f} d  rp = {o.perilune_radius_km:8.1f} km  ra = "
                         f"{o.apolune_radius_km:8.1f} km  nu = {o.stability_index:.6f}  C = {o.jacobi:.8f}  "
                         f"closure = {o.closure:.1e}")
        band, (lo, hi), outer = self.outer_band, self.band_perilune_km, self.outer
        lines.append(f"{len(self.family)} family members; worst closure {max(o.closure for o in self.family):.1e}")
        lines.append(f"outer stable band: {len(band)} family members with perilune {lo:.0f}-{hi:.0f} km, "
                     f"periods {min(o.period_days for o in band):.2f}-{max(o.period_days for o in band):.2f} d; "
                     f"most stable member: perilune {outer.perilune_radius_km:.0f} km, period "
                     f"{outer.period_days:.3f} d, Broucke margin {np.max(np.abs(outer.broucke_indices.real)) - 1:+.3f}")
        lines.append(f"{'perilune [km]':>14} {'apolune [km]':>13} {'period [d]':>11} {'Broucke indices (Re)':>24}")
        for o in band[:: max(1, len(band) // 8)]:
            lines.append(f"{o.perilune_radius_km:14.0f} {o.apolune_radius_km:13.0f} {o.period_days:11.3f} "
                         f"{'  '.join(f'{b:+.3f}' for b in np.sort(o.broucke_indices.real))}")
        return "\n".join(lines)


def halo_family_study(system: CR3BP, step: float) -> HaloFamilyStudy:
    """The 9:2 NRHO, both stable candidates and the southern L2 halo family continued with ``step``."""
    check_system(system)
    step = validation.positive(step, "step")
    family = orbits.l2_southern_halo_family(system, step=step)
    return HaloFamilyStudy(orbits.nrho_9_2(system), orbits.stable_nrho(system), orbits.stable_nrho_outer(system),
                           tuple(family), step)


def _check_study(study, name: str = "study") -> HaloFamilyStudy:
    return validation.instance(study, name, HaloFamilyStudy, "a HaloFamilyStudy (halo_family_study)")


_ORBIT_STYLES = (("nrho", "C0", "9:2 NRHO"), ("stable", "C1", "stable NRHO (inner band)"),
                 ("outer", "C2", "stable NRHO (outer band)"))


def figure_halo_stability(system: CR3BP, study: HaloFamilyStudy):
    """Stability index against perilune radius along the family, with the three orbits and the outer band."""
    check_system(system)
    _check_study(study)
    nrho, stable, outer = study.nrho, study.stable, study.outer
    fig, ax = plt.subplots(figsize=(9.5, 4.6))
    ax.semilogy(study.perilune_km, study.stability_index, "-", color="0.3", label="southern L2 halo family")
    ax.semilogy(nrho.perilune_radius_km, nrho.stability_index, "o", color="C0", ms=8, label="9:2 NRHO")
    ax.semilogy(stable.perilune_radius_km, stable.stability_index, "o", color="C1", ms=8,
                label=r"stable NRHO, inner band edge ($\nu$ = 1)")
    ax.axvspan(*study.band_perilune_km, color="C2", alpha=0.15, label="outer stable band (family members)")
    ax.semilogy(outer.perilune_radius_km, outer.stability_index, "D", color="C2", ms=7,
                label="stable NRHO, outer band (most stable)")
    ax.axvline(system.secondary_radius_km, color="0.6", ls=":", lw=1)
    ax.text(system.secondary_radius_km * 1.05, 2, "lunar radius", color="0.4", rotation=90)
    ax.set_xscale("log")
    ax.set_xticks([2000, 3000, 5000, 10000, 20000, 50000])
    ax.xaxis.set_major_formatter(plt.matplotlib.ticker.ScalarFormatter())
    ax.xaxis.set_minor_formatter(plt.matplotlib.ticker.NullFormatter())
    ax.set_xlabel("perilune radius [km]")
    ax.set_ylabel(r"stability index $\nu$ [-]")
    ax.set_title("Stability along the southern L2 halo family")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    fig.tight_layout()
    return fig


def figure_nrho_family(system: CR3BP, study: HaloFamilyStudy):
    """Analogue of the paper's Fig. 2: NRHO members (perilune < 20,000 km) with the three orbits highlighted."""
    check_system(system)
    _check_study(study)
    fig, axes = plotting.three_plane_axes(figsize=(13, 4.5))
    nrho_like = [o for o in study.family if o.perilune_radius_km < 20000]
    for o in nrho_like[:: max(1, len(nrho_like) // 10)]:
        plotting.plot_three_planes(axes, o.sample(600)[1], system, moon_centred=True, units="km", color="0.7",
                                   lw=0.7)
    for attr, colour, lab in _ORBIT_STYLES:
        plotting.plot_three_planes(axes, getattr(study, attr).sample(1500)[1], system, moon_centred=True,
                                   units="km", color=colour, lw=1.6, label=lab)
    for plane, ax in axes.items():
        plotting.plot_primaries(ax, system, plane, moon_centred=True, units="km", earth=False)
    for plane, ax in axes.items():
        plotting.thousands_km_axes(ax, plane)
    handles, labels = axes["xy"].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), frameon=False)
    fig.suptitle("Southern L2 NRHO family (grey) with the 9:2 (blue) and the two stable candidates (red, green)")
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return fig


# ---------------------------------------------------------------------------------------------------------------
# Observer sites: occultations, surface coverage, all-pairs sweep
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class OrbitVisibility:
    """What the observers see of one target orbit.

    Attributes
    ----------
    l2, dro : OutageStatistics
        Lunar occultations of the line of sight from the L2 and the DRO observer over the span.
    period_days : float
        Target period, days.
    single : ndarray, shape (3,)
        Fraction of the period each default station sees the target.
    best_pair : float
        Best coverage fraction of a pair of the default stations, ``best_pair_stations`` its indices.
    all3 : float
        Coverage fraction of the three default stations together.
    """

    l2: sites.OutageStatistics
    dro: sites.OutageStatistics
    period_days: float
    single: np.ndarray
    best_pair: float
    best_pair_stations: tuple
    all3: float

    @property
    def dro_criteria(self) -> dict:
        """The three criteria written for the paper's "limited, infrequent and short" (notebook 01, section 5)."""
        st = self.dro
        return {"limited": 1 - st.clear_fraction < 0.05, "infrequent": st.mean_interval_days > self.period_days,
                "short": st.longest_h < 6.0}


def observer_visibility(system: CR3BP, targets: dict, samples: int, span_days: float, step_s: float) -> dict:
    """Occultation statistics and default-station coverage for each named target orbit.

    Parameters
    ----------
    targets : dict of str -> PeriodicOrbit
    samples : int
        Points per period for the station coverage.
    span_days, step_s : float
        Span of the occultation statistics (days) and line-of-sight sampling step (s).

    Returns
    -------
    dict of str -> OrbitVisibility
    """
    check_system(system)
    validation.instance(targets, "targets", dict, "a dict of name -> cislunar.cr3bp.orbits.PeriodicOrbit")
    for o in targets.values():
        validation.instance(o, "targets", PeriodicOrbit, "a dict of name -> cislunar.cr3bp.orbits.PeriodicOrbit")
    samples = validation.integer(samples, "samples", minimum=2)
    span_days = validation.positive(span_days, "span_days")
    step_s = validation.positive(step_s, "step_s")
    l2_state, dro_obs, stations = sites.l2_observer_state(system), sites.dro_observer_orbit(system), \
        sites.DEFAULT_STATIONS
    out = {}
    for name, o in targets.items():
        cov = sites.surface_coverage(system, o.sample(samples)[1], stations)
        pairs = {(i, j): cov[[i, j]].any(axis=0).mean() for i in range(3) for j in range(i + 1, 3)}
        best = max(pairs, key=pairs.get)
        out[name] = OrbitVisibility(
            l2=sites.occultation_outages(system, l2_state, o, span_days, step_s),
            dro=sites.occultation_outages(system, dro_obs, o, span_days, step_s),
            period_days=o.period_days, single=cov.mean(axis=1), best_pair=float(pairs[best]),
            best_pair_stations=best, all3=float(cov.any(axis=0).mean()))
    return out


def line_of_sight_samples(span_days: float, step_s: float) -> int:
    """Number of line-of-sight samples of :func:`cislunar.sensing.sites.occultation_outages` over the span."""
    span_days = validation.positive(span_days, "span_days")
    step_s = validation.positive(step_s, "step_s")
    return np.arange(0.0, span_days * 86400 + 0.5 * step_s, step_s).size


def visibility_report(visibility: dict, span_days: float, step_s: float) -> str:
    """The printed station-coverage and occultation tables (``visibility`` from :func:`observer_visibility`)."""
    what = "a dict of name -> OrbitVisibility (observer_visibility)"
    validation.instance(visibility, "visibility", dict, what)
    for v in visibility.values():
        validation.instance(v, "visibility", OrbitVisibility, what)
    span_days = validation.positive(span_days, "span_days")
    step_s = validation.positive(step_s, "step_s")
    stations = sites.DEFAULT_STATIONS
    lines = []
    for name, v in visibility.items():
        lines.append(f"{name:14s} NRHO: stations alone {np.round(100*v.single, 1)}% | best pair of the three "
                     f"{100*v.best_pair:.1f}% ({' + '.join(stations[k].name for k in v.best_pair_stations)}) | "
                     f"all three {100*v.all3:.2f}%")
    lines.append(f"\nline of sight over {span_days} d sampled every {step_s:g} s "
                 f"({line_of_sight_samples(span_days, step_s)} samples per orbit):")
    lines.append(f"{'target':>15} {'observer':>9} {'occulted':>9} {'outages':>8} {'shortest [h]':>13} "
                 f"{'longest [h]':>12} {'mean interval [d]':>18} {'target period [d]':>18}")
    for name, v in visibility.items():
        for who in ("l2", "dro"):
            st = getattr(v, who)
            lines.append(f"{name:>15} {who.upper():>9} {100 * (1 - st.clear_fraction):8.3f}% {st.count:8d} "
                         f"{(st.durations_h.min() if st.count else 0.0):13.2f} {st.longest_h:12.2f} "
                         f"{(f'{st.mean_interval_days:.1f}' if st.count else 'no outage'):>18} "
                         f"{v.period_days:18.3f}")
    return "\n".join(lines)


@dataclass(frozen=True)
class StationSweep:
    """All pairs of a latitude-longitude grid of surface sites against one orbit, and a 1-degree refinement around
    the best pair.

    Attributes
    ----------
    grid_deg : tuple of float
        (latitude, longitude) spacing of the grid, degrees.
    grid_sites, near_sites : tuple of SurfaceStation
    coarse, fine : PairCoverage
        Pair coverage over the grid and over the refinement (samples uniform in time over one period).
    period_days : float
    """

    grid_deg: tuple
    grid_sites: tuple
    near_sites: tuple
    coarse: sites.PairCoverage
    fine: sites.PairCoverage
    period_days: float

    @property
    def n_pairs(self) -> int:
        n = len(self.grid_sites)
        return n * (n - 1) // 2

    @property
    def best_pair_names(self) -> str:
        i, j = self.coarse.best_pair
        return f"{self.grid_sites[i].name} + {self.grid_sites[j].name}"

    @property
    def no_pair_suffices(self) -> bool:
        """No pair of the grid or of the refinement covers every sample."""
        return self.coarse.n_full_pairs == 0 and self.fine.n_full_pairs == 0

    def report(self) -> str:
        sw, fine, (fi, fj) = self.coarse, self.fine, self.fine.best_pair
        return (f"\nall-pairs sweep: {len(self.grid_sites)} sites ({self.grid_deg[0]:g} deg x {self.grid_deg[1]:g} "
                f"deg grid), {self.n_pairs} pairs, {sw.n_samples} samples of the 9:2 NRHO; pairs covering 100 %: "
                f"{sw.n_full_pairs}; best pair {self.best_pair_names} (lat,lon deg) with "
                f"{100 * sw.best_fraction:.2f}% (uncovered {(1 - sw.best_fraction) * self.period_days * 24:.2f} h "
                f"per period); best single site {100 * np.diag(sw.fraction).max():.2f}%\n"
                f"refined around the best pair: {len(self.near_sites)} sites at 1 deg; pairs covering 100 %: "
                f"{fine.n_full_pairs}; best {self.near_sites[fi].name} + {self.near_sites[fj].name} with "
                f"{100 * fine.best_fraction:.2f}%")


def station_pair_sweep(system: CR3BP, orbit: PeriodicOrbit, grid_deg, samples: int) -> StationSweep:
    """Every pair of a ``grid_deg`` = (latitude, longitude) grid of sites (0 deg mask) against ``samples`` points
    of ``orbit`` uniform in time; then every pair of 1-deg sites within +-5 deg latitude and +-10 deg longitude of
    the best pair's two sites (cross pairs included)."""
    check_system(system)
    validation.instance(orbit, "orbit", PeriodicOrbit, "a cislunar.cr3bp.orbits.PeriodicOrbit")
    lat, lon = (validation.positive(g, "grid_deg") for g in validation.as_array(grid_deg, "grid_deg", shape=(2,)))
    try:
        grid_sites = tuple(sites.site_grid(lat, lon))
    except ValueError as exc:
        raise ValueError(f"grid_deg = ({lat:g}, {lon:g}) is not a valid site grid: {exc}") from None
    samples = validation.integer(samples, "samples", minimum=2)
    xs = orbit.sample(samples)[1]
    coarse = sites.pair_coverage(system, xs, grid_sites, min_elevation_deg=0.0)
    bi, bj = coarse.best_pair
    near = tuple(sites.SurfaceStation(f"{la:+g},{lo:+g}", la, lo) for s in (grid_sites[bi], grid_sites[bj])
                 for la in np.arange(max(-90.0, s.latitude_deg - 5), min(90.0, s.latitude_deg + 5) + 0.5, 1.0)
                 for lo in np.arange(s.longitude_deg - 10, s.longitude_deg + 10.5, 1.0))
    fine = sites.pair_coverage(system, xs, near, min_elevation_deg=0.0)
    return StationSweep((lat, lon), grid_sites, near, coarse, fine, orbit.period_days)


@dataclass(frozen=True)
class PeriluneVisibility:
    """Which default station sees the orbit around its perilune (apolune at t = 0, perilune at T/2).

    Attributes
    ----------
    hours : ndarray
        Hours from perilune (30-s grid over +-``half_width_h``).
    rows : tuple of (str, ndarray of bool)
        Each station, the best pair of them, and all three.
    """

    hours: np.ndarray
    rows: tuple
    half_width_h: float

    def intervals(self, seen) -> list:
        """(start, end) in hours from perilune of each run of True in ``seen``."""
        edges = np.flatnonzero(np.diff(np.r_[0, np.asarray(seen).astype(int), 0]))
        return [(self.hours[a], self.hours[b - 1]) for a, b in zip(edges[::2], edges[1::2])]

    def report(self) -> str:
        lines = [f"9:2 NRHO above the horizon within +-{self.half_width_h:g} h of perilune (hours from perilune):"]
        for label, seen in self.rows:
            lines.append(f"  {label:32s} " + ", ".join(f"{a:+.1f} to {b:+.1f}" for a, b in self.intervals(seen)))
        return "\n".join(lines)


def _station_indices(best_pair, n: int) -> tuple:
    """Two distinct indices into the default stations."""
    if isinstance(best_pair, (str, bytes, dict)) or not hasattr(best_pair, "__iter__"):
        raise validation.ArgumentTypeError(f"best_pair must be two station indices; got {type(best_pair).__name__}")
    pair = tuple(validation.integer(k, "best_pair", minimum=0, maximum=n - 1) for k in best_pair)
    if len(pair) != 2 or pair[0] == pair[1]:
        raise ValueError(f"best_pair must be two distinct station indices in 0..{n - 1}; got {pair}")
    return pair


def perilune_visibility(system: CR3BP, orbit: PeriodicOrbit, best_pair, *, half_width_h: float = 6.0
                        ) -> PeriluneVisibility:
    """Visibility of ``orbit`` from each default station within +-``half_width_h`` of perilune (30-s grid)."""
    check_system(system)
    validation.instance(orbit, "orbit", PeriodicOrbit, "a cislunar.cr3bp.orbits.PeriodicOrbit")
    stations = sites.DEFAULT_STATIONS
    best_pair = _station_indices(best_pair, len(stations))
    hw = validation.positive(half_width_h, "half_width_h")
    hours = np.linspace(-hw, hw, round(2 * hw * 120) + 1)
    # the grid starts at apolune (t = 0, where orbit.x0 holds) and the first point is dropped
    x = propagation.propagate(system, orbit.x0, np.r_[0.0, orbit.period / 2 + hours * 3600.0 / system.time_unit_s]).x[1:]
    cov = sites.surface_coverage(system, x, stations)
    rows = [(stations[k].name, cov[k]) for k in range(3)]
    rows += [(f"best pair: {' + '.join(stations[k].name for k in best_pair)}", cov[list(best_pair)].any(axis=0)),
             ("all three", cov.any(axis=0))]
    return PeriluneVisibility(hours, tuple(rows), hw)


def figure_observer_sites(system: CR3BP, study: HaloFamilyStudy, perilune: PeriluneVisibility):
    """The observers and the three orbits in three planes, a zoom on the Moon with the stations' horizons and the
    timeline of station visibility around the 9:2 NRHO's perilune (the paper's Fig. 3 analogue)."""
    check_system(system)
    _check_study(study)
    validation.instance(perilune, "perilune", PeriluneVisibility, "a PeriluneVisibility (perilune_visibility)")
    em = system
    stations = sites.DEFAULT_STATIONS
    l2_state, dro_obs = sites.l2_observer_state(em), sites.dro_observer_orbit(em)
    station_colours = ("C3", "C5", "C7")
    fig = plt.figure(figsize=(13, 9.4))
    grid = fig.add_gridspec(2, 3, height_ratios=[1, 0.9])
    axes = {plane: fig.add_subplot(grid[0, k]) for k, plane in enumerate(("xy", "xz", "yz"))}
    ax_moon = fig.add_subplot(grid[1, 0])
    ax_time = fig.add_subplot(grid[1, 1:])
    for attr, colour, label in _ORBIT_STYLES:
        xs = getattr(study, attr).sample(1500)[1]
        plotting.plot_three_planes(axes, xs, em, moon_centred=True, units="km", color=colour, lw=1.1, label=label)
        plotting.plot_rotating(ax_moon, xs, em, "yz", moon_centred=True, units="km", color=colour, lw=1.3)
    plotting.plot_three_planes(axes, dro_obs.sample(800)[1], em, moon_centred=True, units="km", color="C4", lw=1.2,
                               label="DRO observer")
    p_l2 = (l2_state[:3] - em.secondary_position) * em.length_unit_km
    for plane, ax in axes.items():
        plotting.plot_primaries(ax, em, plane, moon_centred=True, units="km", earth=False)
        i, j = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}[plane]
        ax.plot(p_l2[i], p_l2[j], "*", color="k", ms=12, zorder=4, label="L2 observer")
        plotting.thousands_km_axes(ax, plane)
    axes["yz"].annotate(f"L2 observer (x = +{p_l2[0] / 1e3:.1f}×10³ km)\nprojects onto the Moon here", xy=(0, 0),
                        xytext=(0.97, 0.97), textcoords="axes fraction", ha="right", va="top", fontsize=8,
                        arrowprops={"arrowstyle": "->", "color": "0.3", "lw": 0.8})
    axes["xz"].set_title("x-z plane", fontsize=10)
    axes["xy"].set_title("x-y plane (Earth-Moon plane)", fontsize=10)
    axes["yz"].set_title("y-z plane (viewed from +x, the L2 side)", fontsize=10)
    plotting.plot_primaries(ax_moon, em, "yz", moon_centred=True, units="km", earth=False)
    R = em.secondary_radius_km
    for s, colour in zip(stations, station_colours):
        q = (s.position(em) - em.secondary_position) * em.length_unit_km
        up = q[1:] / np.linalg.norm(q[1:])  # local vertical in the y-z plane (stations lie in it)
        along = np.array([-up[1], up[0]])
        ends = q[1:] + np.outer([-1.0, 1.0], along) * 3 * R
        ax_moon.plot(ends[:, 0], ends[:, 1], "--", color=colour, lw=1)
        ax_moon.plot(q[1], q[2], "^", color=colour, ms=9, mec="k", mew=0.6, zorder=5, label=f"station {s.name}")
    ax_moon.plot([], [], "--", color="0.4", lw=1, label="station horizon (the station sees beyond its line)")
    ax_moon.set_xlim(-2.6 * R, 2.6 * R)
    ax_moon.set_ylim(-2.2 * R, 2.9 * R)
    ax_moon.set_aspect("equal", adjustable="box")
    plotting.thousands_km_axes(ax_moon, "yz")
    ax_moon.set_title("zoom on the Moon, y-z plane (viewed from +x)", fontsize=10)
    rows, hw = perilune.rows, perilune.half_width_h
    for k, ((label, seen), colour) in enumerate(zip(rows, (*station_colours, "0.45", "k"))):
        y = len(rows) - 1 - k
        ax_time.broken_barh([(a, b - a) for a, b in perilune.intervals(seen)], (y - 0.2, 0.4), color=colour)
        ax_time.text(-hw + 0.1, y + 0.27, label, fontsize=8, va="bottom")
    ax_time.axvline(0.0, color="0.3", ls=":", lw=1)
    ax_time.text(0.1, -0.6, "perilune", fontsize=8, color="0.3")
    ax_time.set_xlim(-hw, hw)
    ax_time.set_ylim(-0.7, len(rows) - 0.2)
    ax_time.set_yticks([])
    ax_time.grid(axis="y", visible=False)
    ax_time.set_xlabel("time from the 9:2 NRHO's perilune [h]")
    ax_time.set_title("when each station has the 9:2 NRHO above its horizon (bars)", fontsize=10)
    handles, labels = [], []
    for ax in (axes["xy"], ax_moon):
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    fig.legend(handles, labels, loc="lower center", ncol=5, frameon=False, fontsize=8)
    fig.suptitle("Observer sites and the NRHOs (Moon-centred, rotating frame)")
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    return fig

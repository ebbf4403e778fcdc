"""Panels of Greaves & Scheeres (2021) Figs. 6-13: state errors with 3-sigma bounds, control norm, OCBE metric.

Built from one run of the OCBE (forward and smoothed passes) against its truth; the metric and its limit come from
:mod:`cislunar.estimation.adaptive_ocbe`, the NEES from :mod:`cislunar.estimation.consistency`.  Errors in km and
m/s (or mm/s), control in m/s^2, time in days; rotating barycentric frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.estimation import adaptive_ocbe, ocbe
from cislunar.estimation.consistency import nees
from cislunar.utils import validation

__all__ = ["PASSES", "PanelSeries", "panel_series", "figure_errors", "figure_control_metric"]

# ---------------------------------------------------------------------------------------------------------------
# The paper's figure panels (Figs. 6-13): state errors with 3-sigma bounds, control norm, normalised metric
# ---------------------------------------------------------------------------------------------------------------
#: The two passes every panel figure shows, left to right.
PASSES = ("forward", "smoothed")
_VELOCITY_UNITS = {"m/s": 1e3, "mm/s": 1e6}


@dataclass(frozen=True)
class PanelSeries:
    """What the paper's Figs. 6-13 plot for one OCBE run, in display units.

    Index 0 of every leading axis of length 2 is the forward filter (with the single-step smoothed control of
    Eq. 32), index 1 the full smoother (:data:`PASSES`).

    Attributes
    ----------
    t_days : ndarray, shape (N,)
        Epochs, days from the start of the track.
    t_sub_days : ndarray, shape (N-1, n_sub)
        Sub-grid of each interval on which the control is evaluated, days.
    position_error_km, position_3sigma_km : ndarray, shape (2, N)
        Norm of the position error against the truth and :math:`3\\sqrt{\\mathrm{tr}\\,P_{rr}}`, km.
    velocity_error_m_s, velocity_3sigma_m_s : ndarray, shape (2, N)
        The same for the velocity, m/s.
    control_norm_m_s2 : ndarray, shape (2, N-1, n_sub)
        :math:`\\|\\hat{\\mathbf u}\\|` of the forward (single-step) and smoothed control, m/s^2.
    metric : ndarray, shape (2, N)
        Forward OCBE metric (:func:`cislunar.estimation.adaptive_ocbe.forward_metric`) and smoothed metric (:func:`cislunar.estimation.adaptive_ocbe.smoothed_metric`).
    limit : ndarray, shape (N,)
        99 % detection limit of the forward metric (:func:`cislunar.estimation.adaptive_ocbe.metric_limit`).
    dof : ndarray of int, shape (N,)
        Degrees of freedom (= mean) of the forward metric.
    nees : ndarray, shape (2, N)
        Normalised estimation error squared of both passes (:math:`\\chi^2_6` when consistent).
    """

    t_days: np.ndarray
    t_sub_days: np.ndarray
    position_error_km: np.ndarray
    position_3sigma_km: np.ndarray
    velocity_error_m_s: np.ndarray
    velocity_3sigma_m_s: np.ndarray
    control_norm_m_s2: np.ndarray
    metric: np.ndarray
    limit: np.ndarray
    dof: np.ndarray
    nees: np.ndarray

    @property
    def normalized_metric(self) -> np.ndarray:
        """Both metrics divided by the forward limit (the paper's "normalized OCBE metric"), shape (2, N)."""
        return self.metric / self.limit

    @property
    def mean_line(self) -> np.ndarray:
        """The metric's mean over its limit per epoch (the paper's red line), shape (N,)."""
        return self.dof / self.limit

    def spike_contrast(self, t_days, half_width_days: float = 6 / 24) -> np.ndarray:
        """How much the control norm stands out near ``t_days``: its mean within ``half_width_days`` of it over
        its mean farther away, for the forward and the smoothed control (shape (2,)).

        A contrast near 1 means no spike; the paper's Figs. 11 and 13 show a smoothed spike at the burn.  Means of
        the norm on the sub-grid (not maxima or medians): the forward (single-step) control is a saw-tooth that
        restarts every interval and the smoothed one spreads a burn over the raised-uncertainty intervals, so the
        average level is what distinguishes a spike.  The default half width (6 h) covers the intervals that touch
        an 8-hour window centred on ``t_days`` at a 2-hour cadence.
        """
        t0 = validation.real(t_days, "t_days")
        hw = validation.positive(half_width_days, "half_width_days")
        near = np.abs(self.t_sub_days - t0) <= hw
        if not near.any() or near.all():
            raise ValueError(f"t_days +- half_width_days must cover some but not all of the track; got {t0} +- {hw}")
        return ocbe.spike_contrast(self.t_sub_days, self.control_norm_m_s2, t0, hw)


def panel_series(system: CR3BP, result, truth, control_weight, y, observer_states, model, meas_cov, *,
                 available=None) -> PanelSeries:
    """The panels of the paper's Figs. 6-13 for one run of :func:`cislunar.estimation.ocbe.ocbe_filter_smoother`.

    Parameters
    ----------
    system : CR3BP
        Units (states LU, LU/TU; times TU).
    result : cislunar.estimation.ocbe.OCBEResult
        A run with ``smooth=True``.
    truth : array_like, shape (N, 6)
        True states at the epochs, LU and LU/TU (rotating frame).
    control_weight : float or array_like, shape (N-1,)
        Per-interval control weight :math:`q_n` used in the run, LU^2/TU^3.
    y, observer_states, model, meas_cov, available
        As passed to the run.

    Returns
    -------
    PanelSeries
    """
    check_system(system)
    validation.instance(result, "result", ocbe.OCBEResult, "a cislunar.estimation.ocbe.OCBEResult")
    if result.x_smooth is None:
        raise ValueError("result must come from a run with smooth=True")
    N = result.t.size
    adaptive_ocbe._measurement_inputs(N, y, observer_states, model, meas_cov, available)
    truth = validation.as_array(truth, "truth", shape=(N, 6))
    model = ocbe.check_model(model)
    q = ocbe.control_weights(control_weight, N - 1)
    L, V = system.length_unit_km, system.velocity_unit_km_s * 1e3
    pos_e, pos_s, vel_e, vel_s, nees_passes = [], [], [], [], []
    for x, P in ((result.x_filt, result.P_filt), (result.x_smooth, result.P_smooth)):
        e = x - truth
        pos_e.append(np.linalg.norm(e[:, :3], axis=1) * L)
        vel_e.append(np.linalg.norm(e[:, 3:], axis=1) * V)
        pos_s.append(3 * np.sqrt(np.trace(P[:, :3, :3], axis1=1, axis2=2)) * L)
        vel_s.append(3 * np.sqrt(np.trace(P[:, 3:, 3:], axis1=1, axis2=2)) * V)
        nees_passes.append(nees(x, P, truth))
    acc = system.length_unit_km * 1e3 / system.time_unit_s**2
    control = np.stack([np.linalg.norm(result.control_step, axis=-1), np.linalg.norm(result.control_smooth, axis=-1)])
    m_f, dof = adaptive_ocbe.forward_metric(result, model, available)
    m_s = adaptive_ocbe.smoothed_metric(result, y, observer_states, model, meas_cov, q, available=available)
    day = system.time_unit_s / 86400.0
    return PanelSeries(result.t * day, result.t_sub * day, np.array(pos_e), np.array(pos_s), np.array(vel_e),
                       np.array(vel_s), control * acc, np.stack([m_f, m_s]), adaptive_ocbe.metric_limit(dof), dof, np.array(nees_passes))


def _mark(ax, burn_days, detection_days):
    if burn_days is not None:
        ax.axvline(burn_days, color="0.5", ls=":", lw=1, label="burn")
    for d in detection_days:
        ax.axvline(d, color="C2", ls="--", lw=1, label="detection")


def _legend_below(fig, ax):
    handles, labels = ax.get_legend_handles_labels()
    uniq = dict(zip(labels, handles))
    fig.legend(uniq.values(), uniq.keys(), loc="lower center", ncol=len(uniq), bbox_to_anchor=(0.5, 0.0))
    fig.tight_layout(rect=(0, 0.06, 1, 1))


def figure_errors(panels: PanelSeries, title: str, *, burn_days=None, detection_days=(), velocity_unit="m/s"):
    """Figs. 6, 8, 10, 12 layout: position (top) and velocity (bottom) error norms with their 3-sigma bounds,
    forward filter (left) and smoother (right), on log axes.

    Parameters
    ----------
    panels : PanelSeries
    title : str
        Prefix of the panel titles.
    burn_days : float, optional
        Time of the burn, days (dotted line).
    detection_days : sequence of float
        Times of adaptive detections, days (dashed lines).
    velocity_unit : {"m/s", "mm/s"}

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    validation.instance(panels, "panels", PanelSeries)
    validation.instance(title, "title", str)
    vu = validation.choice(velocity_unit, "velocity_unit", tuple(_VELOCITY_UNITS))
    burn = None if burn_days is None else validation.real(burn_days, "burn_days")
    dets = validation.as_array(detection_days, "detection_days", ndim=(0, 1)).reshape(-1)
    fig = Figure(figsize=(12, 6.5))
    ax = fig.subplots(2, 2, sharex=True)
    scale_v = _VELOCITY_UNITS[vu] / 1e3
    for j, name in enumerate(PASSES):
        rows = ((panels.position_error_km[j], panels.position_3sigma_km[j], "position error [km]"),
                (panels.velocity_error_m_s[j] * scale_v, panels.velocity_3sigma_m_s[j] * scale_v,
                 f"velocity error [{vu}]"))
        for i, (err, sig, lab) in enumerate(rows):
            ax[i, j].semilogy(panels.t_days, err, "C0", label="true error")
            ax[i, j].semilogy(panels.t_days, sig, "C1", label=r"3$\sigma$")
            _mark(ax[i, j], burn, dets)
            ax[i, j].set_ylabel(lab)
        ax[0, j].set_title(f"{title}: {name}")
        ax[1, j].set_xlabel("time from periapsis [d]")
    _legend_below(fig, ax[0, 0])
    return fig


def figure_control_metric(panels: PanelSeries, title: str, *, burn_days=None, detection_days=(),
                          first_pass_metric=None, first_pass_until=None):
    """Figs. 7, 9, 11, 13 layout: control norm (top) and normalised OCBE metric (bottom), forward (left) and
    smoothed (right); the metric (blue) with its mean (red) and the 99 % limit (dashed), as in the paper.

    Parameters
    ----------
    panels : PanelSeries
    title : str
    burn_days : float, optional
    detection_days : sequence of float
    first_pass_metric : array_like, shape (N,), optional
        Forward metric of the adaptive filter's first pass (shown as crosses up to ``first_pass_until``).
    first_pass_until : int, optional
        Last epoch (inclusive) of ``first_pass_metric`` to show (the epoch at which the first reset was declared).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    validation.instance(panels, "panels", PanelSeries)
    validation.instance(title, "title", str)
    burn = None if burn_days is None else validation.real(burn_days, "burn_days")
    dets = validation.as_array(detection_days, "detection_days", ndim=(0, 1)).reshape(-1)
    N = panels.t_days.size
    fp = None if first_pass_metric is None else validation.as_array(first_pass_metric, "first_pass_metric",
                                                                 shape=(N,), finite=False)
    until = N - 1 if first_pass_until is None else validation.integer(first_pass_until, "first_pass_until",
                                                                    minimum=0, maximum=N - 1)
    fig = Figure(figsize=(12, 6.5))
    ax = fig.subplots(2, 2, sharex=True)
    norm = panels.normalized_metric
    for j, name in enumerate(PASSES):
        ax[0, j].semilogy(panels.t_sub_days.ravel(), panels.control_norm_m_s2[j].ravel(), "C0", lw=0.8)
        ax[0, j].set(ylabel=r"control norm $\|\hat{\mathbf{u}}\|$ [m/s$^2$]", title=f"{title}: {name}")
        if j == 0 and fp is not None:
            ax[1, j].semilogy(panels.t_days[:until + 1], fp[:until + 1] / panels.limit[:until + 1], "x",
                              color="0.4", ms=5, label="first pass (up to the first reset)")
        ax[1, j].semilogy(panels.t_days, norm[j], "C0.-", ms=3, lw=0.8, label="metric / limit")
        ax[1, j].plot(panels.t_days, panels.mean_line, "C1", lw=1.2, label="mean / limit")
        ax[1, j].axhline(1.0, color="k", ls="--", lw=0.8, label="99 % limit")
        ax[1, j].set(ylabel="normalised OCBE metric [-]", xlabel="time from periapsis [d]")
        for i in range(2):
            _mark(ax[i, j], burn, dets)
    _legend_below(fig, ax[1, 0])
    return fig

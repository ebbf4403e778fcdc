r"""Adaptive OCBE tuning (Greaves & Scheeres 2021, "Adaptive OCBE Tuning", Figs. 6-9; Lubey & Scheeres 2014).

The adaptive OCBE runs the extended square-root-information OCBE of :mod:`cislunar.ocbe` with a small ("ballistic")
control weight and watches a statistical metric.  When the metric stays above its 99 % limit for three consecutive
epochs, a maneuver is declared **at the first of them** and the control uncertainty of the interval ending at that
epoch is raised until the metric there equals its mean; the filter is then re-run from that epoch on.

The OCBE metric
---------------
At epoch :math:`n+1` the OCBE links the filtered state at :math:`t_n` to the new measurement with the cost
(Lubey & Scheeres 2014, written as twice the OCBE cost so that it is a sum of squares)

.. math::

    M_{n+1} = \underbrace{\boldsymbol\delta_n^\top P_{n|n}^{-1}\boldsymbol\delta_n}_{\text{a priori}}
      + \underbrace{\int_{t_n}^{t_{n+1}}\hat{\mathbf u}^\top\tilde Q^{-1}\hat{\mathbf u}\,dt}_{\text{control}}
      + \underbrace{\mathbf r_{n+1}^\top R_{n+1}^{-1}\mathbf r_{n+1}}_{\text{measurement}},

with :math:`\boldsymbol\delta_n = \mathbf x_{n|n+1}-\mathbf x_{n|n}` the single-step smoothed correction (Eqs.
29-30), :math:`\hat{\mathbf u}` the estimated control (Eq. 32) and :math:`\mathbf r_{n+1} = \delta\mathbf y_{n+1}
- H_{n+1}(\mathbf x_{n+1|n+1}-\mathbf x_{n+1|n})` the (linearised) post-fit residual.  The control term is
exactly :math:`\mathbf w^\top Q^{-1}\mathbf w` with :math:`\mathbf w = \Phi_{xp}\mathbf p_{n|n+1}` the state
change the control produces and :math:`Q = -\Phi_{xp}\Phi_{xx}^\top` (Eq. 17): the minimum-energy control that
moves the state by :math:`\mathbf w` over the interval costs :math:`\mathbf w^\top Q^{-1}\mathbf w`.

**Its law.** :math:`M_{n+1}` is the minimum over :math:`(\boldsymbol\delta_n, \mathbf w)` of a linear least-squares
problem with 6 a-priori pseudo-observations, 6 control pseudo-observations and :math:`m` measurements
(:math:`m` = measurement dimension at that epoch, e.g. 4 for angles and angle rates from one observer).  Completing
the square gives the minimum as the squared Mahalanobis norm of the innovation,

.. math:: M_{n+1} = \delta\mathbf y_{n+1}^\top\bigl(H(\Phi_{xx}P_{n|n}\Phi_{xx}^\top + Q)H^\top + R\bigr)^{-1}
          \delta\mathbf y_{n+1} = \|\mathbf e_{n+1}\|^2,

which in SRI form is the squared norm of the whitened residual :math:`\mathbf e_{x,n+1}` that the Householder
triangularisation of the measurement update leaves below the information array (Eq. 27).  With a correct model
(linear dynamics and measurements, Gaussian prior, process and measurement noise of the assumed covariances) the
innovation is zero-mean Gaussian with exactly that covariance, hence

.. math:: M_{n+1}\sim\chi^2_m,\qquad E[M] = m,\qquad \mathrm{Var}[M] = 2m,

independently from epoch to epoch (innovations are white).  The 99 % limit is :math:`\chi^2_{m,0.99}` (13.28 for
:math:`m = 4`).  Three consecutive exceedances then have probability :math:`10^{-6}` per epoch under the null
hypothesis: over a 79-epoch track (one 9:2 NRHO period at a 2-hour cadence) the chance of any false reset is below
:math:`10^{-4}`.  ``tests/test_adaptive_ocbe.py`` checks the three-term identity and the :math:`\chi^2_m` law
(Kolmogorov-Smirnov) on linear systems.

**The smoothed metric** (Fig. 7, right) is the same cost evaluated with the full smoother's estimates, per epoch
:math:`M^s_{n+1} = \int\hat{\mathbf u}_s^\top\tilde Q^{-1}\hat{\mathbf u}_s\,dt + \mathbf r_{s,n+1}^\top
R^{-1}\mathbf r_{s,n+1}` (plus the a-priori term at epoch 0).  Its per-epoch law is not :math:`\chi^2_m` (smoothed
residuals are shrunk by an epoch-dependent amount), but its sum over the track is the batch least-squares minimum,
which equals :math:`\sum_n M_n` in the linear case: its epoch average is :math:`m`, which is what the figures show
as its "mean".

The reset
---------
After a detection dated to epoch :math:`k` the control weight :math:`q_{k-1}` of the interval
:math:`[t_{k-1}, t_k]` is multiplied by the factor :math:`\alpha \ge 1` that solves
:math:`M_k(\alpha) = m` (the mean).  Because the OCBE reference has zero costate, :math:`\Phi_{xx}` does not depend
on :math:`q` and :math:`Q` is linear in it, so :math:`M_k(\alpha)` is evaluated without re-propagation, in SRI form
(time update with :math:`\alpha Q`, then the measurement update's residual); it decreases monotonically in
:math:`\alpha` and is solved by bracketing in :math:`\log\alpha`.  The filter (and smoother) are then re-run with
the new weight; epochs before :math:`k` are unchanged, and the search for the next detection resumes at
:math:`k+1`.  This is "solving for a state covariance that sets the metric at that epoch equal to its mean" with the
covariance change confined to the OCBE's own degree of freedom, its control uncertainty.

Where the literal rule breaks, and the alternative.  When some measurement components carry no information about
the state (in this package's tracking scenario the angle rates: their 1-s differencing noise is about
:math:`10^5` times their state-driven spread), their whitened noise stays in :math:`M_k(\alpha)` for every
:math:`\alpha`; if it alone exceeds the mean (for two such components, probability :math:`e^{-2}` = 13.5 %) the mean
rule drives :math:`\alpha` up by many orders of magnitude beyond what the burn needs, and the re-linearised filter
then diverges through a chain of further resets.  ``reset="likelihood"`` instead chooses the :math:`\alpha` that
maximises the Gaussian likelihood of the innovation (covariance matching), which inflates only as far as the
explainable part of the innovation asks.  Notebook 09b measures both rules.

Conventions: a detection needs three epochs *with measurements* in a row at or after epoch 1 (epoch 0 has no
interval before it to reset); an epoch without any measurement has no metric (NaN) and breaks a run; a run still
open at the end of the track is not a detection.  Times TU, states LU and LU/TU (rotating frame), control weights
LU^2/TU^3.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import linalg, optimize, stats
from scipy.integrate import simpson

from . import _checks, ocbe, srif
from .dynamics import CR3BP
from .propagation import DEFAULT_TOL, _check_tol

__all__ = ["DETECTION_PROBABILITY", "CONSECUTIVE_EPOCHS", "metric_law", "metric_limit", "MetricTerms",
           "RESET_RULES", "metric_terms", "forward_metric", "smoothed_metric", "first_detection", "Detection",
           "reset_factor", "AdaptiveOCBEResult", "adaptive_ocbe", "adaptive_ocbe_batch", "first_pass_detections",
           "ResetError", "PASSES", "PanelSeries", "panel_series", "figure_errors", "figure_control_metric"]

#: Probability of the metric's detection limit (the paper's 99 %).
DETECTION_PROBABILITY = 0.99
#: Consecutive epochs above the limit that declare a maneuver (dated to the first of them).
CONSECUTIVE_EPOCHS = 3
#: Reset rules of :func:`reset_factor`: the paper's ("mean") and maximum likelihood ("likelihood").
RESET_RULES = ("mean", "likelihood")


class ResetError(RuntimeError):
    """The covariance reset could not set the metric to its mean (picklable).

    Attributes
    ----------
    epoch : int
        Epoch of the detection.
    metric : float
        Metric at that epoch before the reset.
    target : float
        The mean it should be set to.
    reason : str
    """

    def __init__(self, epoch: int, metric: float, target: float, reason: str):
        super().__init__(f"covariance reset at epoch {epoch} failed (metric {metric:.6g}, target {target:.6g}): "
                         f"{reason}")
        self.epoch, self.metric, self.target, self.reason = int(epoch), float(metric), float(target), str(reason)

    def __reduce__(self):
        return (type(self), (self.epoch, self.metric, self.target, self.reason))


def metric_law(dof: int):
    """The OCBE metric's law under a correct model: ``scipy.stats.chi2(dof)`` (dof = measurement dimension)."""
    return stats.chi2(_checks.integer(dof, "dof", minimum=1))


def metric_limit(dof, probability: float = DETECTION_PROBABILITY):
    """Detection limit :math:`\\chi^2_{m,p}` of the metric (elementwise for an array of dofs; NaN where dof = 0)."""
    p = _checks.in_range(probability, "probability", 0.0, 1.0, closed=False)
    d = _checks.as_array(dof, "dof", ndim=None)
    if np.any(d < 0) or np.any(d != np.round(d)):
        raise ValueError("dof must be non-negative integers")
    out = np.where(d > 0, stats.chi2.ppf(p, np.maximum(d, 1)), np.nan)
    return float(out) if out.ndim == 0 else out


@dataclass(frozen=True)
class MetricTerms:
    """The three terms of the OCBE metric at one epoch and the whitened innovation they sum to.

    Attributes
    ----------
    prior, control, measurement : float
        A-priori, control and measurement terms (dimensionless squared Mahalanobis norms).
    total : float
        Their sum, the OCBE metric.
    innovation : float
        :math:`\\|\\mathbf e\\|^2` of the SRI measurement update (equal to ``total``).
    delta : ndarray, shape (n,)
        Single-step smoothed correction :math:`\\mathbf x_{n|n+1}-\\mathbf x_{n|n}`.
    w : ndarray, shape (n,)
        State change produced by the estimated control over the interval.
    """

    prior: float
    control: float
    measurement: float
    total: float
    innovation: float
    delta: np.ndarray
    w: np.ndarray


def metric_terms(S, Phi, Q, H, dy, meas_cov) -> MetricTerms:
    """Lubey's OCBE metric at one epoch from the SRI quantities of one time and measurement update.

    Parameters
    ----------
    S : array_like, shape (n, n)
        Upper-triangular square-root information matrix of the filtered state at :math:`t_n` (deviation form,
        mean zero).
    Phi : array_like, shape (n, n)
        State transition :math:`\\Phi_{xx}(t_{n+1}, t_n)`.
    Q : array_like, shape (n, n)
        OCBE process-noise-like term :math:`-\\Phi_{xp}\\Phi_{xx}^\\top` (positive definite).
    H : array_like, shape (m, n)
        Measurement Jacobian at the predicted state.
    dy : array_like, shape (m,)
        Pre-fit residual :math:`\\mathbf y - h(\\mathbf x_{n+1|n})`.
    meas_cov : array_like, shape (m, m)

    Returns
    -------
    MetricTerms
    """
    S = _checks.upper_triangular(S, "S")
    n = S.shape[0]
    Phi = _checks.as_array(Phi, "Phi", shape=(n, n))
    Q = _checks.spd(Q, "Q", n=n)
    H = _checks.as_array(H, "H", ndim=(2,))
    if H.shape[1] != n:
        raise ValueError(f"H must have {n} columns; got shape {H.shape}")
    dy = _checks.as_array(dy, "dy", shape=(H.shape[0],))
    eye = np.eye(n)
    S_bar, _, term = srif.time_update(S, np.zeros(n), Phi, eye, Q)
    S_new, b_new, e = srif.measurement_update(S_bar, np.zeros(n), H, dy, meas_cov)
    dx_next = srif.covariance_from_sri(S_new, b_new)[0]
    S1, b1 = srif.smoother_step(S_new, b_new, Phi, eye, term)
    delta = srif.covariance_from_sri(S1, b1)[0]
    w = dx_next - Phi @ delta
    Wq = srif.sri_from_covariance(np.zeros(n), Q, name="Q")[0]
    Wr = srif.sri_from_covariance(np.zeros(H.shape[0]), meas_cov, name="meas_cov")[0]
    prior = float(np.sum((S @ delta) ** 2))
    control = float(np.sum((Wq @ w) ** 2))
    meas = float(np.sum((Wr @ (dy - H @ dx_next)) ** 2))
    return MetricTerms(prior, control, meas, prior + control + meas, e**2, delta, w)


def _dof(model, available, N: int, K: int) -> np.ndarray:
    if available is None:
        return np.full(N, K * model.dim, dtype=int)
    return np.asarray(available, bool).reshape(N, K).sum(axis=1) * model.dim


def _availability(available, N: int, K: int) -> np.ndarray:
    """``available`` as an (N, K) bool array (all True when None), refused by name when malformed."""
    if available is None:
        return np.ones((N, K), bool)
    if isinstance(available, (str, bytes)) or available is None:
        raise _checks.ArgumentTypeError(f"available must be an array of bool; got {type(available).__name__}")
    try:
        a = np.asarray(available)
    except ValueError:
        raise _checks.ArgumentTypeError("available must be an array of bool (a regular, non-ragged array)") from None
    if a.dtype != bool:
        raise _checks.ArgumentTypeError(f"available must be an array of bool; got dtype {a.dtype}")
    if a.shape not in ((N, K),) + (((N,),) if K == 1 else ()):
        raise ValueError(f"available must have shape ({N}, {K}); got {a.shape}")
    return a.reshape(N, K)


def _measurement_inputs(N: int, y, observer_states, model, meas_cov, available):
    """Checked measurement arrays of a run: y (N, K, m), observers (N, K, 6), R (N, m, m), availability (N, K)."""
    model = ocbe.check_model(model)
    obs = _checks.as_array(observer_states, "observer_states", ndim=(2, 3), last=6)
    obs = obs[:, None, :] if obs.ndim == 2 else obs
    if obs.shape[0] != N:
        raise ValueError(f"observer_states must have {N} epochs; got shape {obs.shape}")
    K = obs.shape[1]
    yy = _checks.as_array(y, "y", ndim=(2, 3), finite=False)
    yy = yy[:, None, :] if yy.ndim == 2 else yy
    if yy.shape != (N, K, model.dim):
        raise ValueError(f"y must have shape ({N}, {model.dim}) or ({N}, {K}, {model.dim}); got {yy.shape}")
    avail = _availability(available, N, K)
    if not np.all(np.isfinite(yy[avail])):
        raise ValueError("y contains NaN or infinite values where measurements are available")
    R = _checks.as_array(meas_cov, "meas_cov", ndim=(2, 3))
    R = np.broadcast_to(R, (N, model.dim, model.dim)) if R.shape == (model.dim, model.dim) else R
    if R.shape != (N, model.dim, model.dim):
        raise ValueError(f"meas_cov must have shape ({model.dim}, {model.dim}) or ({N}, {model.dim}, {model.dim}); "
                         f"got {R.shape}")
    _checks.spd(R, "meas_cov", batch=True)
    return yy, obs, R, avail


def forward_metric(result, model, available=None):
    """Forward OCBE metric per epoch and its degrees of freedom.

    Parameters
    ----------
    result : cislunar.ocbe.OCBEResult or cislunar.detection.BatchOCBEResult
        Filter output; the metric is the squared whitened innovation ``residual_norms**2`` (see the module
        docstring for the identity with the three-term cost).
    model : cislunar.measurements.MeasurementModel
    available : array_like of bool, shape (N, K), optional
        Observer availability used in the run (default: one observer, always).

    Returns
    -------
    metric : ndarray, shape (N,) or (B, N)
        NaN at epochs without measurements.
    dof : ndarray of int, shape (N,)
    """
    model = ocbe.check_model(model)
    if not hasattr(result, "residual_norms"):
        raise _checks.ArgumentTypeError("result must be a cislunar.ocbe.OCBEResult or a "
                                        f"cislunar.detection.BatchOCBEResult; got {type(result).__name__}")
    r = _checks.as_array(result.residual_norms, "result.residual_norms", ndim=(1, 2))
    N = r.shape[-1]
    if available is None:
        dof = _dof(model, None, N, 1)
    else:
        try:
            size = int(np.size(available))
        except ValueError:  # ragged: refused by name below
            size = 0
        K = max(size // N, 1)
        dof = _dof(model, _availability(available, N, K), N, K)
    return np.where(dof > 0, r**2, np.nan), dof


def smoothed_metric(result, y, observer_states, model, meas_cov, control_weight, *, available=None):
    """Smoothed OCBE metric per epoch (control + measurement terms with the full smoother's estimates).

    Parameters
    ----------
    result : cislunar.ocbe.OCBEResult
        A run with ``smooth=True``.
    y, observer_states, model, meas_cov, available
        As passed to :func:`cislunar.ocbe.ocbe_filter_smoother`.
    control_weight : float or array_like, shape (N-1,)
        Per-interval :math:`q_n` of that run, LU^2/TU^3.

    Returns
    -------
    ndarray, shape (N,)
        Epoch 0 carries the a-priori term and its measurement term; the control integral uses Simpson's rule on
        the run's sub-grid.  See the module docstring for its (epoch-averaged) mean.
    """
    _checks.instance(result, "result", ocbe.OCBEResult, "a cislunar.ocbe.OCBEResult")
    if result.x_smooth is None:
        raise ValueError("result must come from a run with smooth=True")
    model = ocbe.check_model(model)
    N = result.t.size
    yy, obs, R, avail = _measurement_inputs(N, y, observer_states, model, meas_cov, available)
    qs = ocbe.control_weights(control_weight, N - 1)
    out = np.zeros(N)
    for k in range(N):
        vis = np.flatnonzero(avail[k])
        if vis.size:
            W = srif.sri_from_covariance(np.zeros(model.dim), R[k], name="meas_cov")[0]
            r = model.residual(yy[k, vis], model(obs[k, vis], result.x_smooth[k]))
            out[k] = float(np.sum((r @ W.T) ** 2))
        else:
            out[k] = np.nan
    u2 = np.sum(result.control_smooth**2, axis=-1) / qs[:, None]
    out[1:] = np.where(np.isnan(out[1:]), 0.0, out[1:]) + simpson(u2, x=result.t_sub, axis=-1)
    S0 = srif.sri_from_covariance(np.zeros(6), result.P_pred[0], name="P0")[0]
    out[0] += float(np.sum((S0 @ (result.x_smooth[0] - result.x_pred[0])) ** 2))
    return out


def first_detection(metric, limit, *, start: int = 1, consecutive: int = CONSECUTIVE_EPOCHS):
    """First epoch ``k >= start`` with ``metric > limit`` at ``k, ..., k + consecutive - 1`` (None if none).

    NaN metrics (epochs without measurements) never exceed the limit.
    """
    m = _checks.as_array(metric, "metric", ndim=(1,), finite=False)
    lim = np.broadcast_to(_checks.as_array(limit, "limit", ndim=None, finite=False), m.shape)
    c = _checks.integer(consecutive, "consecutive", minimum=1)
    s = _checks.integer(start, "start", minimum=0)
    over = np.zeros(m.size, bool)
    ok = np.isfinite(m) & np.isfinite(lim)
    over[ok] = m[ok] > lim[ok]
    run = 0
    for k in range(s, m.size):
        run = run + 1 if over[k] else 0
        if run == c:
            return k - c + 1
    return None


@dataclass(frozen=True)
class Detection:
    """One maneuver detection of the adaptive OCBE.

    Attributes
    ----------
    epoch : int
        Epoch the detection is dated to (first of the consecutive exceedances).
    declared_epoch : int
        Epoch at which the rule fired (``epoch + consecutive - 1``).
    time : float
        ``t[epoch]``, TU.
    factor : float
        Multiplier :math:`\\alpha` applied to the control weight of interval ``epoch - 1``.
    metric_before, metric_after : float
        Metric at ``epoch`` before the reset and in the re-run (equal to the mean ``dof`` under the mean rule).
    """

    epoch: int
    declared_epoch: int
    time: float
    factor: float
    metric_before: float
    metric_after: float


def reset_factor(system: CR3BP, t, k: int, x_filt_prev, P_filt_prev, y_k, observers_k, model, meas_cov,
                 control_weight: float, *, rule: str = "mean", target: float | None = None, n_sub: int = 9,
                 tol: float = DEFAULT_TOL, max_factor: float = 1e40):
    """Control-weight multiplier :math:`\\alpha` of the reset at epoch ``k``.

    ``rule="mean"`` (the paper's): the metric at ``k`` becomes ``target`` (default: its mean, the dof).
    ``rule="likelihood"``: :math:`\\alpha` maximises the likelihood of the innovation,
    :math:`\\min_\\alpha \\log\\det C(\\alpha) + \\delta\\mathbf y^\\top C(\\alpha)^{-1}\\delta\\mathbf y`
    with :math:`C(\\alpha) = H(\\Phi P\\Phi^\\top + \\alpha Q)H^\\top + R` (covariance matching; clipped at 1).  It
    differs from the mean rule when some measurement components cannot be explained by any state error (here the
    angle rates, whose noise dwarfs their signal): their noise stays in the metric whatever :math:`\\alpha`, and
    when it alone exceeds the mean (for two such dofs, probability :math:`e^{-2}` = 13.5 %) the mean rule needs an
    absurd :math:`\\alpha`; the likelihood rule inflates only as far as the explainable part asks.

    Parameters
    ----------
    system : CR3BP
    t : array_like, shape (N,)
        Epochs, TU.
    k : int
        Detection epoch (>= 1).
    x_filt_prev, P_filt_prev : array_like
        Filtered state (6,) and covariance (6, 6) at ``t[k-1]``.
    y_k, observers_k : array_like, shapes (K, m) and (K, 6)
        Measurements and observer states at ``t[k]`` of the observers that measured.
    model, meas_cov
        Measurement model and one observer's covariance (m, m).
    control_weight : float
        :math:`q_{k-1}` used in the run, LU^2/TU^3.
    target : float, optional
        Metric value to reach (default ``K * model.dim``, the mean).

    Returns
    -------
    factor : float
        :math:`\\alpha \\ge 1`.
    metric_at_one : float
        Metric recomputed with :math:`\\alpha = 1` (equals the run's value; a consistency check).

    Raises
    ------
    ResetError
        When even ``max_factor`` leaves the metric above the target.
    """
    _checks.system(system)
    t = _checks.time_grid(t, "t", increasing=True)
    k = _checks.integer(k, "k", minimum=1, maximum=t.size - 1)
    q = _checks.positive(control_weight, "control_weight")
    P = _checks.spd(P_filt_prev, "P_filt_prev", n=6)
    x_prev = _checks.as_state(x_filt_prev, "x_filt_prev", batch=False)
    model = ocbe.check_model(model)
    obs = _checks.as_array(observers_k, "observers_k", ndim=(1, 2), last=6).reshape(-1, 6)
    yk = _checks.as_array(y_k, "y_k", ndim=(1, 2), last=model.dim)
    if yk.size != obs.shape[0] * model.dim:
        raise ValueError(f"y_k must hold {obs.shape[0]} measurement(s) of length {model.dim}; got shape {yk.shape}")
    yk = yk.reshape(obs.shape[0], model.dim)
    meas_cov = _checks.spd(meas_cov, "meas_cov", n=model.dim)
    grid = np.linspace(t[k - 1], t[k], _checks.integer(n_sub, "n_sub", minimum=2))
    tr = ocbe.ocbe_transition(system, x_prev, grid, q, tol=_check_tol(tol))
    Phi = tr.phi[-1, :6, :6]
    Q = ocbe.ocbe_process_noise(tr.phi[-1])
    val, _, Ht = model.evaluate(obs, tr.x[-1])
    dy = model.residual(yk, val).reshape(-1)
    H = Ht.reshape(-1, 6)
    Rk = np.kron(np.eye(obs.shape[0]), np.asarray(meas_cov, float))
    S = srif.sri_from_covariance(np.zeros(6), P, name="P_filt_prev")[0]
    eye = np.eye(6)
    target = float(H.shape[0]) if target is None else _checks.positive(target, "target")
    _checks.choice(rule, "rule", RESET_RULES)

    def update(log_alpha):
        S_bar = srif.time_update(S, np.zeros(6), Phi, eye, np.exp(log_alpha) * Q)[0]
        S_new, _, e = srif.measurement_update(S_bar, np.zeros(6), H, dy, Rk)
        return S_bar, S_new, e**2

    def metric(log_alpha):
        return update(log_alpha)[2]

    m1 = metric(0.0)
    hi = np.log(_checks.positive(max_factor, "max_factor"))
    if rule == "likelihood":
        # The innovation covariance C(alpha) is m x m and R keeps it SPD for every alpha, so its Cholesky factor gives
        # log det C and the whitened innovation directly.  (The determinant lemma on the SRI factors is equivalent
        # but its time-updated factor underflows once alpha Q dwarfs the prior, alpha ~ 1e30 here.)
        HPH = H @ Phi @ P @ Phi.T @ H.T
        HQH = H @ Q @ H.T

        def nll(la):
            L = np.linalg.cholesky(HPH + np.exp(la) * HQH + Rk)
            w = linalg.solve_triangular(L, dy, lower=True)
            return 2 * np.sum(np.log(np.diag(L))) + float(w @ w)

        grid = np.linspace(0.0, hi, 161)
        vals = np.array([nll(g) for g in grid])
        i = int(np.argmin(vals))
        if i == 0:
            return 1.0, m1
        lo_b, hi_b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
        la = optimize.minimize_scalar(nll, bounds=(lo_b, hi_b), method="bounded",
                                      options={"xatol": 1e-10}).x
        return float(np.exp(la)), m1
    if m1 <= target:
        return 1.0, m1
    if metric(hi) > target:
        raise ResetError(k, m1, target, f"metric still {metric(hi):.3g} with the control weight x {max_factor:.0e}")
    la = optimize.brentq(lambda a: metric(a) - target, 0.0, hi, xtol=1e-12, rtol=1e-12)
    return float(np.exp(la)), m1


@dataclass(frozen=True)
class AdaptiveOCBEResult:
    """Output of :func:`adaptive_ocbe`.

    Attributes
    ----------
    result : cislunar.ocbe.OCBEResult
        The final pass (with every reset applied).
    control_weight : ndarray, shape (N-1,)
        Final per-interval control weights, LU^2/TU^3.
    metric : ndarray, shape (N,)
        Forward OCBE metric of the final pass (NaN without measurements).
    dof : ndarray of int, shape (N,)
        Its degrees of freedom (= its mean).
    limit : ndarray, shape (N,)
        Detection limit per epoch.
    metric_first_pass : ndarray, shape (N,)
        Forward metric of the first (non-adaptive) pass.
    smoothed_metric : ndarray or None, shape (N,)
    detections : tuple of Detection
    passes : int
        Filter runs made (detections + 1).
    """

    result: ocbe.OCBEResult
    control_weight: np.ndarray
    metric: np.ndarray
    dof: np.ndarray
    limit: np.ndarray
    metric_first_pass: np.ndarray
    smoothed_metric: np.ndarray | None
    detections: tuple = field(default_factory=tuple)
    passes: int = 1

    @property
    def normalized_metric(self) -> np.ndarray:
        """Metric divided by the detection limit (the paper's "normalized OCBE metric")."""
        return self.metric / self.limit

    @property
    def normalized_smoothed_metric(self):
        return None if self.smoothed_metric is None else self.smoothed_metric / self.limit


def adaptive_ocbe(system: CR3BP, t, y, observer_states, model, meas_cov, x0, P0, control_weight, *, available=None,
                  probability: float = DETECTION_PROBABILITY, consecutive: int = CONSECUTIVE_EPOCHS,
                  reset: str = "mean", n_sub: int = 9, smooth: bool = True, tol: float = DEFAULT_TOL,
                  max_resets: int = 50) -> AdaptiveOCBEResult:
    """Adaptive extended SRI OCBE: detection by the metric rule and covariance reset (module docstring).

    Parameters are those of :func:`cislunar.ocbe.ocbe_filter_smoother` (``control_weight`` is the starting, usually
    ballistic, tuning: scalar or per interval, LU^2/TU^3), plus

    probability : float
        Probability of the metric limit (0.99 in the paper).
    consecutive : int
        Exceedances in a row that declare a maneuver (3 in the paper).
    reset : {"mean", "likelihood"}
        Reset rule (:func:`reset_factor`): the paper's (metric set to its mean) or maximum likelihood.
    max_resets : int
        Safety bound on the number of resets.
    """
    _checks.system(system)
    model = ocbe.check_model(model)
    t = _checks.time_grid(t, "t", increasing=True)
    N = t.size
    q = ocbe.control_weights(control_weight, N - 1).copy()
    consecutive = _checks.integer(consecutive, "consecutive", minimum=1)
    max_resets = _checks.integer(max_resets, "max_resets", minimum=0)
    _checks.choice(reset, "reset", RESET_RULES)
    _checks.in_range(probability, "probability", 0.0, 1.0, closed=False)
    yy, obs3, R, avail = _measurement_inputs(N, y, observer_states, model, meas_cov, available)

    def run():
        return ocbe.ocbe_filter_smoother(system, t, y, observer_states, model, meas_cov, x0, P0, q,
                                         available=available, n_sub=n_sub, smooth=smooth, tol=tol)

    res = run()  # validates every remaining argument by name
    y3 = yy
    metric, dof = forward_metric(res, model, avail)
    limit = metric_limit(dof, probability)
    first = metric.copy()
    detections, start = [], 1
    while True:
        k = first_detection(metric, limit, start=start, consecutive=consecutive)
        if k is None:
            break
        if len(detections) >= max_resets:
            raise ResetError(k, metric[k], dof[k], f"more than max_resets = {max_resets} resets")
        vis = np.flatnonzero(avail[k])
        factor, m1 = reset_factor(system, t, k, res.x_filt[k - 1], res.P_filt[k - 1], y3[k, vis], obs3[k, vis],
                                  model, R[k], q[k - 1], rule=reset, n_sub=n_sub, tol=tol)
        before = metric[k]
        q[k - 1] *= factor
        res = run()
        metric = forward_metric(res, model, avail)[0]
        detections.append(Detection(k, k + consecutive - 1, float(t[k]), factor, float(before), float(metric[k])))
        start = k + 1
    sm = smoothed_metric(res, y, observer_states, model, meas_cov, q, available=available) if smooth else None
    return AdaptiveOCBEResult(res, q, metric, dof, limit, first, sm, tuple(detections), len(detections) + 1)


def adaptive_ocbe_batch(system: CR3BP, t, y, observer_states, model, meas_cov, x0, P0, control_weight, *,
                        probability: float = DETECTION_PROBABILITY, consecutive: int = CONSECUTIVE_EPOCHS,
                        reset: str = "mean", n_sub: int = 9, tol: float = DEFAULT_TOL, max_resets: int = 50):
    """The adaptive OCBE for B trials in lockstep on :func:`cislunar.detection.ocbe_batch` (one observer).

    Same rule and reset as :func:`adaptive_ocbe`, trial by trial; each pass re-runs the whole batch with the
    updated per-trial weights (trials without a new detection reproduce their previous pass).

    Parameters
    ----------
    y : array_like, shape (B, N, m)
    x0 : array_like, shape (B, 6)
    P0 : array_like, shape (6, 6) or (B, 6, 6)
    control_weight : scalar or array_like, shape (N-1,) or (B, N-1)
    Others as in :func:`cislunar.detection.ocbe_batch`.

    Returns
    -------
    result : cislunar.detection.BatchOCBEResult
        Final pass.
    control_weight : ndarray, shape (B, N-1)
    metric : ndarray, shape (B, N)
    detections : list of tuple of Detection
        Per trial.
    """
    from . import detection

    _checks.system(system)
    model = ocbe.check_model(model)
    t = _checks.time_grid(t, "t", increasing=True)
    N = t.size
    yy = _checks.as_array(y, "y", ndim=(3,))
    B = yy.shape[0]
    q = ocbe.control_weights(control_weight, N - 1, batch=B).copy()
    obs = _checks.as_array(observer_states, "observer_states", shape=(N, 6))
    consecutive = _checks.integer(consecutive, "consecutive", minimum=1)
    max_resets = _checks.integer(max_resets, "max_resets", minimum=0)
    _checks.choice(reset, "reset", RESET_RULES)
    _checks.in_range(probability, "probability", 0.0, 1.0, closed=False)

    def run():
        return detection.ocbe_batch(system, t, yy, obs, model, meas_cov, x0, P0, q, n_sub=n_sub, tol=tol)

    res = run()
    metric, dof = forward_metric(res, model)
    limit = metric_limit(dof, probability)
    start = np.ones(B, int)
    dets = [[] for _ in range(B)]
    while True:
        ks = [first_detection(metric[b], limit, start=int(start[b]), consecutive=consecutive) for b in range(B)]
        todo = [b for b in range(B) if ks[b] is not None]
        if not todo:
            break
        before = {}
        for b in todo:
            k = ks[b]
            if len(dets[b]) >= max_resets:
                raise ResetError(k, metric[b, k], dof[k], f"trial {b}: more than max_resets = {max_resets} resets")
            factor, _ = reset_factor(system, t, k, res.x_filt[b, k - 1], res.P_filt[b, k - 1], yy[b, k], obs[k],
                                     model, meas_cov, q[b, k - 1], rule=reset, n_sub=n_sub, tol=tol)
            q[b, k - 1] *= factor
            before[b] = (k, factor, float(metric[b, k]))
        res = run()
        metric = forward_metric(res, model)[0]
        for b, (k, factor, m0) in before.items():
            dets[b].append(Detection(k, k + consecutive - 1, float(t[k]), factor, m0, float(metric[b, k])))
            start[b] = k + 1
    return res, q, metric, [tuple(d) for d in dets]


def first_pass_detections(system: CR3BP, t, y, observer_states, model, meas_cov, x0, P0, control_weight, *,
                          probability: float = DETECTION_PROBABILITY, consecutive: int = CONSECUTIVE_EPOCHS,
                          n_sub: int = 9, tol: float = DEFAULT_TOL) -> np.ndarray:
    """Epoch of the adaptive OCBE's first detection for B trials, from one batched pass (-1 where none).

    Until its first reset the adaptive filter is the plain OCBE with the starting tuning, so its first detection
    (and with it the detection delay of a single maneuver) does not depend on the reset rule: one pass of
    :func:`cislunar.detection.ocbe_batch` and the three-epoch rule (:func:`first_detection`, from epoch 1) give it
    for every trial.  Arguments as in :func:`adaptive_ocbe_batch` (one observer).

    Returns
    -------
    ndarray of int, shape (B,)
        Epoch the first detection is dated to, or -1 when the metric never stays above its limit for
        ``consecutive`` epochs within the track.
    """
    from . import detection

    _checks.system(system)
    model = ocbe.check_model(model)
    consecutive = _checks.integer(consecutive, "consecutive", minimum=1)
    _checks.in_range(probability, "probability", 0.0, 1.0, closed=False)
    res = detection.ocbe_batch(system, t, y, observer_states, model, meas_cov, x0, P0, control_weight, n_sub=n_sub,
                               tol=tol)
    metric, dof = forward_metric(res, model)
    limit = metric_limit(dof, probability)
    out = [first_detection(m, limit, consecutive=consecutive) for m in metric]
    return np.array([-1 if k is None else k for k in out], dtype=int)


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
        Forward OCBE metric (:func:`forward_metric`) and smoothed metric (:func:`smoothed_metric`).
    limit : ndarray, shape (N,)
        99 % detection limit of the forward metric (:func:`metric_limit`).
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
        t0 = _checks.real(t_days, "t_days")
        hw = _checks.positive(half_width_days, "half_width_days")
        near = np.abs(self.t_sub_days - t0) <= hw
        if not near.any() or near.all():
            raise ValueError(f"t_days +- half_width_days must cover some but not all of the track; got {t0} +- {hw}")
        return ocbe.spike_contrast(self.t_sub_days, self.control_norm_m_s2, t0, hw)


def panel_series(system: CR3BP, result, truth, control_weight, y, observer_states, model, meas_cov, *,
                 available=None) -> PanelSeries:
    """The panels of the paper's Figs. 6-13 for one run of :func:`cislunar.ocbe.ocbe_filter_smoother`.

    Parameters
    ----------
    system : CR3BP
        Units (states LU, LU/TU; times TU).
    result : cislunar.ocbe.OCBEResult
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
    _checks.system(system)
    _checks.instance(result, "result", ocbe.OCBEResult, "a cislunar.ocbe.OCBEResult")
    if result.x_smooth is None:
        raise ValueError("result must come from a run with smooth=True")
    N = result.t.size
    _measurement_inputs(N, y, observer_states, model, meas_cov, available)
    truth = _checks.as_array(truth, "truth", shape=(N, 6))
    model = ocbe.check_model(model)
    q = ocbe.control_weights(control_weight, N - 1)
    from . import tracking

    L, V = system.length_unit_km, system.velocity_unit_km_s * 1e3
    pos_e, pos_s, vel_e, vel_s, nees = [], [], [], [], []
    for x, P in ((result.x_filt, result.P_filt), (result.x_smooth, result.P_smooth)):
        e = x - truth
        pos_e.append(np.linalg.norm(e[:, :3], axis=1) * L)
        vel_e.append(np.linalg.norm(e[:, 3:], axis=1) * V)
        pos_s.append(3 * np.sqrt(np.trace(P[:, :3, :3], axis1=1, axis2=2)) * L)
        vel_s.append(3 * np.sqrt(np.trace(P[:, 3:, 3:], axis1=1, axis2=2)) * V)
        nees.append(tracking.nees(x, P, truth))
    acc = system.length_unit_km * 1e3 / system.time_unit_s**2
    control = np.stack([np.linalg.norm(result.control_step, axis=-1), np.linalg.norm(result.control_smooth, axis=-1)])
    m_f, dof = forward_metric(result, model, available)
    m_s = smoothed_metric(result, y, observer_states, model, meas_cov, q, available=available)
    day = system.time_unit_s / 86400.0
    return PanelSeries(result.t * day, result.t_sub * day, np.array(pos_e), np.array(pos_s), np.array(vel_e),
                       np.array(vel_s), control * acc, np.stack([m_f, m_s]), metric_limit(dof), dof, np.array(nees))


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

    _checks.instance(panels, "panels", PanelSeries)
    _checks.instance(title, "title", str)
    vu = _checks.choice(velocity_unit, "velocity_unit", tuple(_VELOCITY_UNITS))
    burn = None if burn_days is None else _checks.real(burn_days, "burn_days")
    dets = _checks.as_array(detection_days, "detection_days", ndim=(0, 1)).reshape(-1)
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

    _checks.instance(panels, "panels", PanelSeries)
    _checks.instance(title, "title", str)
    burn = None if burn_days is None else _checks.real(burn_days, "burn_days")
    dets = _checks.as_array(detection_days, "detection_days", ndim=(0, 1)).reshape(-1)
    N = panels.t_days.size
    fp = None if first_pass_metric is None else _checks.as_array(first_pass_metric, "first_pass_metric",
                                                                 shape=(N,), finite=False)
    until = N - 1 if first_pass_until is None else _checks.integer(first_pass_until, "first_pass_until",
                                                                    minimum=0, maximum=N - 1)
    fig = Figure(figsize=(12, 6.5))
    ax = fig.subplots(2, 2, sharex=True)
    norm = panels.normalized_metric
    for j, name in enumerate(PASSES):
        ax[0, j].semilogy(panels.t_sub_days.ravel(), panels.control_norm_m_s2[j].ravel(), "C0", lw=0.8)
        ax[0, j].set(ylabel=r"control norm $\|\hat{\mathbf{u}}\|$ [m/s$^2$]", title=f"{title}: {name}")
        if j == 0 and fp is not None:
            ax[1, j].semilogy(panels.t_days[:until + 1], fp[:until + 1] / panels.limit[:until + 1], "x",
                              color="0.4", ms=5, label="before the reset")
        ax[1, j].semilogy(panels.t_days, norm[j], "C0.-", ms=3, lw=0.8, label="metric / limit")
        ax[1, j].plot(panels.t_days, panels.mean_line, "C1", lw=1.2, label="mean / limit")
        ax[1, j].axhline(1.0, color="k", ls="--", lw=0.8, label="99 % limit")
        ax[1, j].set(ylabel="normalised OCBE metric [-]", xlabel="time from periapsis [d]")
        for i in range(2):
            _mark(ax[i, j], burn, dets)
    _legend_below(fig, ax[1, 0])
    return fig

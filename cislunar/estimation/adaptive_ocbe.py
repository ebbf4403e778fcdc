r"""Adaptive OCBE tuning (Greaves & Scheeres 2021, "Adaptive OCBE Tuning", Figs. 6-9; Lubey & Scheeres 2014).

The adaptive OCBE runs the extended square-root-information OCBE of :mod:`cislunar.estimation.ocbe` with a small ("ballistic")
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
:math:`10^{-4}`.  ``tests/estimation/test_adaptive_ocbe.py`` checks the three-term identity and the :math:`\chi^2_m` law
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

The state-covariance reset.  ``reset="inflate"`` reads "solves for a state covariance" literally: the predicted
state covariance of epoch :math:`k`, :math:`P^-_k = \Phi_{xx}P_{k-1|k-1}\Phi_{xx}^\top + Q`, is multiplied by the
factor :math:`\beta \ge 1` that solves

.. math:: M_k(\beta) = \delta\mathbf y_k^\top\bigl(\beta H P^-_k H^\top + R\bigr)^{-1}\delta\mathbf y_k = m

(monotone decreasing in :math:`\beta`, solved in :math:`\log\beta`), and the filter restarts at :math:`t_k` from
the prior :math:`(\mathbf x^-_k, \beta P^-_k)`; the control weights are not changed, so epochs before :math:`k` are
unchanged and only epochs from :math:`k` on are re-run.  Every state direction is inflated, position included, not
only the velocity directions the control weight opens.  With ``smooth=True`` the smoother runs over each segment
between such restarts separately (the OCBE's backward pass has no term for an inflated prior), so smoothed estimates
before a restart do not see the data after it.  Like the mean rule, it sets the metric to its mean and so meets the
same pure-noise components when they alone exceed the mean.

Conventions: a detection needs three epochs *with measurements* in a row at or after epoch 1 (epoch 0 has no
interval before it to reset); an epoch without any measurement has no metric (NaN) and breaks a run; a run still
open at the end of the track is not a detection.  Times TU, states LU and LU/TU (rotating frame), control weights
LU^2/TU^3.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace

import numpy as np
from scipy import linalg, optimize, stats
from scipy.integrate import simpson

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.propagation import DEFAULT_TOL, _check_tol
from cislunar.estimation import ocbe, srif
from cislunar.estimation.batched_ocbe import ocbe_batch
from cislunar.utils import validation

__all__ = ["DETECTION_PROBABILITY", "CONSECUTIVE_EPOCHS", "metric_law", "metric_limit", "MetricTerms",
           "RESET_RULES", "metric_terms", "forward_metric", "smoothed_metric", "first_detection", "Detection",
           "reset_factor", "AdaptiveOCBEResult", "adaptive_ocbe", "adaptive_ocbe_batch", "first_pass_detections",
           "ResetError", "INFLATE", "ALL_RESET_RULES"]

#: Probability of the metric's detection limit (the paper's 99 %).
DETECTION_PROBABILITY = 0.99
#: Consecutive epochs above the limit that declare a maneuver (dated to the first of them).
CONSECUTIVE_EPOCHS = 3
#: Reset rules of :func:`reset_factor`: the paper's ("mean") and maximum likelihood ("likelihood").
RESET_RULES = ("mean", "likelihood")
#: The reset that inflates the predicted state covariance until the metric equals its mean (module docstring).
INFLATE = "inflate"
#: Every reset of :func:`adaptive_ocbe`: the control-weight rules of :data:`RESET_RULES` and :data:`INFLATE`.
ALL_RESET_RULES = RESET_RULES + (INFLATE,)


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
    return stats.chi2(validation.integer(dof, "dof", minimum=1))


def metric_limit(dof, probability: float = DETECTION_PROBABILITY):
    """Detection limit :math:`\\chi^2_{m,p}` of the metric (elementwise for an array of dofs; NaN where dof = 0)."""
    p = validation.in_range(probability, "probability", 0.0, 1.0, closed=False)
    d = validation.as_array(dof, "dof", ndim=None)
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
    S = validation.upper_triangular(S, "S")
    n = S.shape[0]
    Phi = validation.as_array(Phi, "Phi", shape=(n, n))
    Q = validation.spd(Q, "Q", n=n)
    H = validation.as_array(H, "H", ndim=(2,))
    if H.shape[1] != n:
        raise ValueError(f"H must have {n} columns; got shape {H.shape}")
    dy = validation.as_array(dy, "dy", shape=(H.shape[0],))
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
        raise validation.ArgumentTypeError(f"available must be an array of bool; got {type(available).__name__}")
    try:
        a = np.asarray(available)
    except ValueError:
        raise validation.ArgumentTypeError("available must be an array of bool (a regular, non-ragged array)") from None
    if a.dtype != bool:
        raise validation.ArgumentTypeError(f"available must be an array of bool; got dtype {a.dtype}")
    if a.shape not in ((N, K),) + (((N,),) if K == 1 else ()):
        raise ValueError(f"available must have shape ({N}, {K}); got {a.shape}")
    return a.reshape(N, K)


def _measurement_inputs(N: int, y, observer_states, model, meas_cov, available):
    """Checked measurement arrays of a run: y (N, K, m), observers (N, K, 6), R (N, m, m), availability (N, K)."""
    model = ocbe.check_model(model)
    obs = validation.as_array(observer_states, "observer_states", ndim=(2, 3), last=6)
    obs = obs[:, None, :] if obs.ndim == 2 else obs
    if obs.shape[0] != N:
        raise ValueError(f"observer_states must have {N} epochs; got shape {obs.shape}")
    K = obs.shape[1]
    yy = validation.as_array(y, "y", ndim=(2, 3), finite=False)
    yy = yy[:, None, :] if yy.ndim == 2 else yy
    if yy.shape != (N, K, model.dim):
        raise ValueError(f"y must have shape ({N}, {model.dim}) or ({N}, {K}, {model.dim}); got {yy.shape}")
    avail = _availability(available, N, K)
    if not np.all(np.isfinite(yy[avail])):
        raise ValueError("y contains NaN or infinite values where measurements are available")
    R = validation.as_array(meas_cov, "meas_cov", ndim=(2, 3))
    R = np.broadcast_to(R, (N, model.dim, model.dim)) if R.shape == (model.dim, model.dim) else R
    if R.shape != (N, model.dim, model.dim):
        raise ValueError(f"meas_cov must have shape ({model.dim}, {model.dim}) or ({N}, {model.dim}, {model.dim}); "
                         f"got {R.shape}")
    validation.spd(R, "meas_cov", batch=True)
    return yy, obs, R, avail


def forward_metric(result, model, available=None):
    """Forward OCBE metric per epoch and its degrees of freedom.

    Parameters
    ----------
    result : cislunar.estimation.ocbe.OCBEResult or cislunar.estimation.batched_ocbe.BatchOCBEResult
        Filter output; the metric is the squared whitened innovation ``residual_norms**2`` (see the module
        docstring for the identity with the three-term cost).
    model : cislunar.sensing.measurements.MeasurementModel
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
        raise validation.ArgumentTypeError("result must be a cislunar.estimation.ocbe.OCBEResult or a "
                                        f"cislunar.estimation.batched_ocbe.BatchOCBEResult; got {type(result).__name__}")
    r = validation.as_array(result.residual_norms, "result.residual_norms", ndim=(1, 2))
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
    result : cislunar.estimation.ocbe.OCBEResult
        A run with ``smooth=True``.
    y, observer_states, model, meas_cov, available
        As passed to :func:`cislunar.estimation.ocbe.ocbe_filter_smoother`.
    control_weight : float or array_like, shape (N-1,)
        Per-interval :math:`q_n` of that run, LU^2/TU^3.

    Returns
    -------
    ndarray, shape (N,)
        Epoch 0 carries the a-priori term and its measurement term; the control integral uses Simpson's rule on
        the run's sub-grid.  See the module docstring for its (epoch-averaged) mean.
    """
    validation.instance(result, "result", ocbe.OCBEResult, "a cislunar.estimation.ocbe.OCBEResult")
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
    m = validation.as_array(metric, "metric", ndim=(1,), finite=False)
    lim = np.broadcast_to(validation.as_array(limit, "limit", ndim=None, finite=False), m.shape)
    c = validation.integer(consecutive, "consecutive", minimum=1)
    s = validation.integer(start, "start", minimum=0)
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
        Multiplier :math:`\\alpha` applied to the control weight of interval ``epoch - 1`` (``reset="inflate"``: the
        multiplier :math:`\\beta` of the predicted state covariance at ``epoch``).
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

    ``rule="inflate"``: instead the multiplier :math:`\\beta` of the predicted state covariance
    :math:`P^-_k = \\Phi P\\Phi^\\top + Q` that sets the metric to ``target`` (module docstring).

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
    check_system(system)
    t = validation.time_grid(t, "t", increasing=True)
    k = validation.integer(k, "k", minimum=1, maximum=t.size - 1)
    q = validation.positive(control_weight, "control_weight")
    P = validation.spd(P_filt_prev, "P_filt_prev", n=6)
    x_prev = validation.as_state(x_filt_prev, "x_filt_prev", batch=False)
    model = ocbe.check_model(model)
    obs = validation.as_array(observers_k, "observers_k", ndim=(1, 2), last=6).reshape(-1, 6)
    yk = validation.as_array(y_k, "y_k", ndim=(1, 2), last=model.dim)
    if yk.size != obs.shape[0] * model.dim:
        raise ValueError(f"y_k must hold {obs.shape[0]} measurement(s) of length {model.dim}; got shape {yk.shape}")
    yk = yk.reshape(obs.shape[0], model.dim)
    meas_cov = validation.spd(meas_cov, "meas_cov", n=model.dim)
    grid = np.linspace(t[k - 1], t[k], validation.integer(n_sub, "n_sub", minimum=2))
    tr = ocbe.ocbe_transition(system, x_prev, grid, q, tol=_check_tol(tol))
    Phi = tr.phi[-1, :6, :6]
    Q = ocbe.ocbe_process_noise(tr.phi[-1])
    val, _, Ht = model.evaluate(obs, tr.x[-1])
    dy = model.residual(yk, val).reshape(-1)
    H = Ht.reshape(-1, 6)
    Rk = np.kron(np.eye(obs.shape[0]), np.asarray(meas_cov, float))
    S = srif.sri_from_covariance(np.zeros(6), P, name="P_filt_prev")[0]
    eye = np.eye(6)
    target = float(H.shape[0]) if target is None else validation.positive(target, "target")
    validation.choice(rule, "rule", ALL_RESET_RULES)

    zero = np.zeros(6)
    # alpha = 1 through the public updates (they check Phi, Q and Rk by name), every other alpha through their
    # unchecked kernels: the same arithmetic
    S_bar = srif.time_update(S, zero, Phi, eye, Q)[0]
    m1 = srif.measurement_update(S_bar, zero, H, dy, Rk)[2] ** 2

    def metric(log_alpha):
        S_bar = srif._time_update(S, zero, Phi, eye, np.exp(log_alpha) * Q)[0]
        return float(srif._measurement_update(S_bar, zero, H, dy, Rk)[2]) ** 2

    hi = np.log(validation.positive(max_factor, "max_factor"))
    if rule == INFLATE:
        return _inflation_factor(k, H @ _predicted_covariance(Phi, P, Q) @ H.T, Rk, dy, target, hi, max_factor), m1
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


def _predicted_covariance(Phi, P, Q) -> np.ndarray:
    """The OCBE's predicted state covariance :math:`\\Phi P\\Phi^\\top + Q` (symmetrised)."""
    Pp = Phi @ P @ Phi.T + Q
    return 0.5 * (Pp + Pp.T)


def _inflation_factor(k, HPH, Rk, dy, target, hi, max_factor) -> float:
    """:math:`\\beta \\ge 1` with :math:`\\delta y^\\top(\\beta HP^-H^\\top + R)^{-1}\\delta y` = ``target`` (brentq in
    :math:`\\log\\beta`; 1 when the metric is already at most ``target``)."""
    def metric(log_beta):
        L = np.linalg.cholesky(np.exp(log_beta) * HPH + Rk)
        w = linalg.solve_triangular(L, dy, lower=True)
        return float(w @ w)

    m1 = metric(0.0)
    if m1 <= target:
        return 1.0
    if metric(hi) > target:
        raise ResetError(k, m1, target, f"metric still {metric(hi):.3g} with the state covariance x {max_factor:.0e}")
    return float(np.exp(optimize.brentq(lambda a: metric(a) - target, 0.0, hi, xtol=1e-12, rtol=1e-12)))


def _inflated_prior(system, t, k, x_prev, P_prev, q, beta, n_sub, tol):
    """Prior of the restart at ``t[k]`` after an inflation reset: the predicted state and :math:`\\beta P^-_k`
    (the same prediction :func:`reset_factor` solved on)."""
    tr = ocbe.ocbe_transition(system, x_prev, np.linspace(t[k - 1], t[k], n_sub), q, tol=tol)
    P = _predicted_covariance(tr.phi[-1, :6, :6], np.asarray(P_prev, float), ocbe.ocbe_process_noise(tr.phi[-1]))
    return tr.x[-1].copy(), beta * P


def _reset(system, t, k, x_prev, P_prev, *args, **kw):
    """:func:`reset_factor` inside the adaptive filters: a filtered covariance that has become numerically singular
    (after a large inflation) is a failed reset (:class:`ResetError`), not a bad argument."""
    try:
        validation.spd(P_prev, "P_filt_prev", n=6)
    except ValueError as exc:
        raise ResetError(k, np.nan, np.nan, str(exc)) from None
    return reset_factor(system, t, k, x_prev, P_prev, *args, **kw)


#: Fields of an OCBE result per epoch (N) and per interval (N-1); the rest (t, t_sub, z) are rebuilt when stitching.
_EPOCH_FIELDS = ("x_pred", "P_pred", "x_filt", "P_filt", "x_smooth", "P_smooth", "residual_norms")
_INTERVAL_FIELDS = ("costate_step", "costate_smooth", "control_step", "control_smooth")


def _stitch(res, k: int, tail):
    """Result ``res`` up to epoch ``k`` (exclusive) followed by ``tail``, a run over ``t[k:]`` (single-trial
    :class:`ocbe.OCBEResult`); Eq. 33's integrals recomputed over the whole track."""
    new = {}
    for f in fields(res):
        v = getattr(res, f.name)
        if f.name in _EPOCH_FIELDS + _INTERVAL_FIELDS and v is not None:
            new[f.name] = np.concatenate([v[:k], getattr(tail, f.name)], axis=0)
    new["z_step"] = float(ocbe._control_integral(res.t_sub, new["control_step"]))
    if res.control_smooth is not None:
        new["z_smooth"] = float(ocbe._control_integral(res.t_sub, new["control_smooth"]))
    return replace(res, **new)


@dataclass(frozen=True)
class AdaptiveOCBEResult:
    """Output of :func:`adaptive_ocbe`.

    Attributes
    ----------
    result : cislunar.estimation.ocbe.OCBEResult
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

    Parameters are those of :func:`cislunar.estimation.ocbe.ocbe_filter_smoother` (``control_weight`` is the starting, usually
    ballistic, tuning: scalar or per interval, LU^2/TU^3), plus

    probability : float
        Probability of the metric limit (0.99 in the paper).
    consecutive : int
        Exceedances in a row that declare a maneuver (3 in the paper).
    reset : {"mean", "likelihood", "inflate"}
        Reset rule (:func:`reset_factor`): the paper's (metric set to its mean by the control weight), maximum
        likelihood, or the state-covariance inflation (metric set to its mean by inflating the predicted state
        covariance and restarting the filter there; module docstring).
    max_resets : int
        Safety bound on the number of resets.
    """
    check_system(system)
    model = ocbe.check_model(model)
    t = validation.time_grid(t, "t", increasing=True)
    N = t.size
    q = ocbe.control_weights(control_weight, N - 1).copy()
    consecutive = validation.integer(consecutive, "consecutive", minimum=1)
    max_resets = validation.integer(max_resets, "max_resets", minimum=0)
    validation.choice(reset, "reset", ALL_RESET_RULES)
    validation.in_range(probability, "probability", 0.0, 1.0, closed=False)
    yy, obs3, R, avail = _measurement_inputs(N, y, observer_states, model, meas_cov, available)

    def restart(k, x_k, P_k):
        return ocbe.ocbe_filter_smoother(system, t[k:], yy[k:], obs3[k:], model, R[k:], x_k, P_k, q[k:],
                                         available=avail[k:], n_sub=n_sub, smooth=smooth, tol=tol)

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
        factor, m1 = _reset(system, t, k, res.x_filt[k - 1], res.P_filt[k - 1], y3[k, vis], obs3[k, vis],
                                  model, R[k], q[k - 1], rule=reset, n_sub=n_sub, tol=tol)
        before = metric[k]
        if reset == INFLATE:
            x_k, P_k = _inflated_prior(system, t, k, res.x_filt[k - 1], res.P_filt[k - 1], q[k - 1], factor, n_sub, tol)
            res = _stitch(res, k, restart(k, x_k, P_k))
        else:
            q[k - 1] *= factor
            res = run()
        metric = forward_metric(res, model, avail)[0]
        detections.append(Detection(k, k + consecutive - 1, float(t[k]), factor, float(before), float(metric[k])))
        start = k + 1
    sm = smoothed_metric(res, y, observer_states, model, meas_cov, q, available=available) if smooth else None
    return AdaptiveOCBEResult(res, q, metric, dof, limit, first, sm, tuple(detections), len(detections) + 1)


def _reset_rules(reset, B: int) -> list:
    """``reset`` (one rule, or one per trial) as a list of B rules, refused by name when malformed."""
    if not isinstance(reset, (list, tuple, np.ndarray)):
        return [validation.choice(reset, "reset", ALL_RESET_RULES)] * B
    rules = list(np.asarray(reset, dtype=object).reshape(-1))
    if len(rules) != B:
        raise ValueError(f"reset must name one rule or {B} rules (one per trial); got {len(rules)}")
    return [validation.choice(r, f"reset[{i}]", ALL_RESET_RULES) for i, r in enumerate(rules)]


def adaptive_ocbe_batch(system: CR3BP, t, y, observer_states, model, meas_cov, x0, P0, control_weight, *,
                        probability: float = DETECTION_PROBABILITY, consecutive: int = CONSECUTIVE_EPOCHS,
                        reset: str | list = "mean", n_sub: int = 9, tol: float = DEFAULT_TOL, max_resets: int = 50,
                        smooth: bool = True, on_failure: str = "raise"):
    """The adaptive OCBE for B trials in lockstep on :func:`cislunar.estimation.batched_ocbe.ocbe_batch` (one observer).

    Same rule and reset as :func:`adaptive_ocbe`, trial by trial; each pass re-runs, as one batch, only the trials
    with a new detection (each trial's result does not depend on the other trials of a batch, so the others keep
    their previous pass).  Parameters not listed below are as in
    :func:`cislunar.estimation.batched_ocbe.ocbe_batch`.

    Parameters
    ----------
    y : array_like, shape (B, N, m)
    x0 : array_like, shape (B, 6)
    P0 : array_like, shape (6, 6) or (B, 6, 6)
    control_weight : scalar or array_like, shape (N-1,) or (B, N-1)
    reset : str or sequence of str
        Reset rule (:func:`reset_factor`, one of :data:`ALL_RESET_RULES`), for all trials or one per trial (B
        entries).  An ``"inflate"`` trial re-runs only from its detection epoch, batched with the other trials
        reset at the same epoch.
    smooth : bool
        Run the smoother in every pass (``False``: the forward filter only, as ``adaptive_ocbe(..., smooth=False)``;
        the detections use the forward metric only, so they do not depend on it).
    on_failure : {"raise", "flag"}
        A trial that fails, numerically (as in :func:`cislunar.estimation.batched_ocbe.ocbe_batch`) or in its reset
        (:class:`ResetError`: the reset cannot reach its target, or more than ``max_resets`` resets), stops the whole
        batch (``"raise"``) or is flagged and dropped while the others go on (``"flag"``): its epoch and message are
        in the result's ``failure_epoch`` / ``failure`` (the epoch of the detection for a :class:`ResetError`, as
        :func:`adaptive_ocbe` raises it), its arrays and metric NaN; its detections are those made before the failure.

    Returns
    -------
    result : cislunar.estimation.batched_ocbe.BatchOCBEResult
        Final pass of each trial.
    control_weight : ndarray, shape (B, N-1)
    metric : ndarray, shape (B, N)
    detections : list of tuple of Detection
        Per trial.
    """
    check_system(system)
    model = ocbe.check_model(model)
    t = validation.time_grid(t, "t", increasing=True)
    N = t.size
    yy = validation.as_array(y, "y", ndim=(3,))
    B = yy.shape[0]
    q = ocbe.control_weights(control_weight, N - 1, batch=B).copy()
    obs = validation.as_array(observer_states, "observer_states", shape=(N, 6))
    consecutive = validation.integer(consecutive, "consecutive", minimum=1)
    max_resets = validation.integer(max_resets, "max_resets", minimum=0)
    rules = _reset_rules(reset, B)
    validation.in_range(probability, "probability", 0.0, 1.0, closed=False)
    smooth = validation.boolean(smooth, "smooth")
    flag = validation.choice(on_failure, "on_failure", ("raise", "flag")) == "flag"

    res = ocbe_batch(system, t, yy, obs, model, meas_cov, x0, P0, q, n_sub=n_sub, tol=tol, smooth=smooth,
                     on_failure=on_failure)  # validates every remaining argument by name
    x0a, P0a = np.asarray(x0, float), np.asarray(P0, float)
    out = {f.name: (None if getattr(res, f.name) is None else np.array(getattr(res, f.name)))
           for f in fields(res) if f.name not in ("t_sub", "failure_epoch", "failure")}
    fail_epoch = np.full(B, -1) if res.failure_epoch is None else np.array(res.failure_epoch, int)
    fail_msg = [""] * B if res.failure is None else [str(m) for m in res.failure]
    metric, dof = forward_metric(res, model)
    limit = metric_limit(dof, probability)
    start = np.ones(B, int)
    dets = [[] for _ in range(B)]

    def drop(b, k, exc):
        fail_epoch[b], fail_msg[b] = k, str(exc)
        for v in out.values():
            if v is not None and v.dtype.kind == "f":
                v[b] = np.nan
        metric[b] = np.nan

    while True:
        ks = [None if fail_epoch[b] >= 0 else
              first_detection(metric[b], limit, start=int(start[b]), consecutive=consecutive) for b in range(B)]
        before, restarts = {}, {}
        for b in (b for b in range(B) if ks[b] is not None):
            k = ks[b]
            try:
                if len(dets[b]) >= max_resets:
                    raise ResetError(k, metric[b, k], dof[k], f"trial {b}: more than max_resets = {max_resets} resets")
                factor, _ = _reset(system, t, k, out["x_filt"][b, k - 1], out["P_filt"][b, k - 1], yy[b, k],
                                         obs[k], model, meas_cov, q[b, k - 1], rule=rules[b], n_sub=n_sub, tol=tol)
            except ResetError as exc:
                if not flag:
                    raise
                drop(b, k, exc)
                continue
            if rules[b] == INFLATE:
                restarts[b] = _inflated_prior(system, t, k, out["x_filt"][b, k - 1], out["P_filt"][b, k - 1],
                                              q[b, k - 1], factor, n_sub, tol)
            else:
                q[b, k - 1] *= factor
            before[b] = (k, factor, float(metric[b, k]))
        if not before:
            break
        groups = [(0, np.array(sorted(b for b in before if rules[b] != INFLATE)))]
        for k in sorted({before[b][0] for b in restarts}):
            groups.append((k, np.array(sorted(b for b in restarts if before[b][0] == k))))
        for k0, idx in groups:
            if idx.size == 0:
                continue
            if k0 == 0:
                sub = ocbe_batch(system, t, yy[idx], obs, model, meas_cov, x0a[idx],
                                 P0a[idx] if P0a.ndim == 3 else P0a, q[idx], n_sub=n_sub, tol=tol, smooth=smooth,
                                 on_failure=on_failure)
            else:
                sub = ocbe_batch(system, t[k0:], yy[idx, k0:], obs[k0:], model, meas_cov,
                                 np.array([restarts[b][0] for b in idx]), np.array([restarts[b][1] for b in idx]),
                                 q[idx, k0:], n_sub=n_sub, tol=tol, smooth=smooth, on_failure=on_failure)
            for name, v in out.items():
                if v is None:
                    continue
                if name in ("z_step", "z_smooth"):
                    continue
                v[idx, k0:] = getattr(sub, name)
            for name, ctl in (("z_step", "control_step"), ("z_smooth", "control_smooth")):
                if out.get(name) is not None and out.get(ctl) is not None:
                    out[name][idx] = (getattr(sub, name) if k0 == 0 else
                                      ocbe._control_integral(res.t_sub, out[ctl][idx]))
            # the squared residual norms, as forward_metric gives them, NaN for a trial that failed in this re-run
            metric[idx, k0:] = np.asarray(sub.residual_norms, float) ** 2
            if sub.failure_epoch is not None:
                for i, b in enumerate(idx):
                    if sub.failure_epoch[i] >= 0:  # the whole trial NaN, as a re-run from epoch 0 leaves it
                        drop(b, k0 + int(sub.failure_epoch[i]), sub.failure[i])
        for b, (k, factor, m0) in before.items():
            if fail_epoch[b] < 0:
                dets[b].append(Detection(k, k + consecutive - 1, float(t[k]), factor, m0, float(metric[b, k])))
                start[b] = k + 1
    failures = (dict(failure_epoch=fail_epoch, failure=np.array(fail_msg, dtype=str))
                if flag or res.failure_epoch is not None else {})
    return replace(res, **out, **failures), q, metric, [tuple(d) for d in dets]


def first_pass_detections(system: CR3BP, t, y, observer_states, model, meas_cov, x0, P0, control_weight, *,
                          probability: float = DETECTION_PROBABILITY, consecutive: int = CONSECUTIVE_EPOCHS,
                          n_sub: int = 9, tol: float = DEFAULT_TOL) -> np.ndarray:
    """Epoch of the adaptive OCBE's first detection for B trials, from one batched pass (-1 where none).

    Until its first reset the adaptive filter is the plain OCBE with the starting tuning, so its first detection
    (and with it the detection delay of a single maneuver) does not depend on the reset rule: one pass of
    :func:`cislunar.estimation.batched_ocbe.ocbe_batch` and the three-epoch rule (:func:`first_detection`, from epoch 1) give it
    for every trial.  Arguments as in :func:`adaptive_ocbe_batch` (one observer).

    Returns
    -------
    ndarray of int, shape (B,)
        Epoch the first detection is dated to, or -1 when the metric never stays above its limit for
        ``consecutive`` epochs within the track.
    """
    check_system(system)
    model = ocbe.check_model(model)
    consecutive = validation.integer(consecutive, "consecutive", minimum=1)
    validation.in_range(probability, "probability", 0.0, 1.0, closed=False)
    res = ocbe_batch(system, t, y, observer_states, model, meas_cov, x0, P0, control_weight, n_sub=n_sub,
                     tol=tol, smooth=False)  # the forward metric needs the filter only
    metric, dof = forward_metric(res, model)
    limit = metric_limit(dof, probability)
    out = [first_detection(m, limit, consecutive=consecutive) for m in metric]
    return np.array([-1 if k is None else k for k in out], dtype=int)

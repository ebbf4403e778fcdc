r"""Test case 2 without a keep-out: what the convex subproblem hits, and two remedies that are not a keep-out (issue
22 item 4; notebook 06, section 11).

Without the 424 km keep-out, SCvx on test case 2 does not converge: its iterates head for a target and a convex
subproblem fails about half a kilometre from it.  This module says why, and tries two smooth remedies.

What is here:

* :func:`passing_state`: the window-start state whose ballistic arc passes a target at a given distance at one
  measurement time (Newton on the STM).
* :func:`pass_scan`: along such passes, the MI, the norms of its gradient and Hessian, and the conditioning of the
  whitened (range, range-rate) Jacobian of the passed target at the pass; the log-log slopes against the pass
  distance (the range-rate row grows like :math:`1/\rho`, the MI gradient like :math:`1/\rho`, its curvature like
  :math:`1/\rho^2`).
* :func:`free_run_diagnosis`: the run without keep-out, recording every reference; the solver's status at the
  failure, the closest approach and the MI gradient and curvature at each reference, and the scale of the
  information term of the convex subproblem against its other terms (what Clarabel must resolve).
* :class:`RangeNoiseInformation`: a remedy, a range-dependent measurement noise :math:`\sigma(\rho) =
  \sigma\sqrt{1 + (\rho_c/\rho)^2}` (:func:`cislunar.sensing.information.range_noise_scale`) in the window's MI,
  with its exact gradient (product rule through the noise), in the information-model protocol of
  :func:`cislunar.guidance.scvx.solve_scvx`.  Far from the targets (:math:`\rho \gg \rho_c`) it is the paper's
  model; near one, the information of that target vanishes like :math:`\rho/\rho_c` instead of diverging.
* :class:`RegularisedJacobianInformation`: the other remedy, narrower: only the :math:`1/\rho` of the range-rate
  row's position part becomes :math:`1/\sqrt{\rho^2+\rho_c^2}`
  (:func:`cislunar.sensing.information.regularised_range_rate_jacobian`), the noise and every other entry the
  paper's.  It tests the diagnosis itself: if removing that one term lets SCvx converge, that term is what fails.
* :func:`remedy_runs`: test case 2 over a grid of weights with the remedies and without any keep-out, compared with
  the keep-out plans (:func:`remedy_table`).

Units: non-dimensional (LU, TU) unless a name says ``_km``; Earth-Moon rotating frame.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp.propagation import propagate, propagate_stm
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.papers.wolf_jones import test_case_studies as studies
from cislunar.sensing import information as info_mod
from cislunar.utils import validation

__all__ = [
    "FreeRunDiagnosis",
    "PassScan",
    "REMEDIES",
    "RangeNoiseInformation",
    "RegularisedJacobianInformation",
    "RemedyRun",
    "brief_outcome",
    "free_run_diagnosis",
    "pass_scan",
    "passing_state",
    "remedy_runs",
    "remedy_table",
]


# --------------------------------------------------------------------------------------------------------------
# the remedy: range-dependent noise in the window's MI
# --------------------------------------------------------------------------------------------------------------
class _RemedyInformation:
    """What the two remedies share: the window of an inner
    :class:`~cislunar.papers.wolf_jones.scenarios.WindowInformation` (P0, the fixed Q, R and its linearisations),
    the protocol of :func:`cislunar.guidance.scvx.solve_scvx`
    (``model(x, 0) -> I`` in nats, ``model(x, 1) -> (I, dI/dx)``, ``model.hessian(x)`` by central differences of the
    gradient) and the range scale :math:`\\rho_c`; a subclass says how the window's rows change near a target."""

    def __init__(self, inner: wj.WindowInformation, range_scale_km: float, *, hessian_step: float | None = None):
        self.inner = validation.instance(inner, "inner", wj.WindowInformation)
        self.range_scale_km = validation.positive(range_scale_km, "range_scale_km")
        self.range_scale = float(inner.system.km_to_lu(self.range_scale_km))
        self.hessian_step = (inner.hessian_step if hessian_step is None
                             else validation.positive(hessian_step, "hessian_step"))
        lin = inner.linearization(inner.x_reference)
        self._kernel = info_mod.InformationKernel(lin.P0, lin.Q, lin.R, lin.t.size)

    @property
    def targets_x0(self):
        return self.inner.targets_x0

    @property
    def system(self):
        return self.inner.system

    def hessian(self, x) -> np.ndarray:
        """Symmetrised central differences of the gradient, (6, 6), nats per unit^2."""
        x = validation.as_state(x, "x", batch=False)
        h = self.hessian_step
        G = np.array([self(x + h * e, 1)[1] - self(x - h * e, 1)[1] for e in np.eye(6)]) / (2.0 * h)
        return 0.5 * (G + G.T)


class RangeNoiseInformation(_RemedyInformation):
    r"""The MI of a :class:`~cislunar.papers.wolf_jones.scenarios.WindowInformation` window with a range-dependent
    measurement noise :math:`\sigma(\rho) = \sigma\sqrt{1 + (\rho_c/\rho)^2}` on every row of each target.

    Implements the protocol of :func:`cislunar.guidance.scvx.solve_scvx`: ``model(x, 0) -> I`` (nats),
    ``model(x, 1) -> (I, dI/dx)`` and ``model.hessian(x)`` (central differences of the gradient).  The fixed
    ingredients (P0, the fixed Q, R) are the inner model's; only the row scale of :math:`H` depends on the range.

    Parameters
    ----------
    inner : WindowInformation
    range_scale_km : float
        :math:`\rho_c`, km (> 0).
    hessian_step : float
        Central-difference step of :meth:`hessian` (non-dimensional, all six components; default the inner's).
    """

    #: The remedy's name in :func:`remedy_runs` and its tables.
    name = "range noise"

    def __call__(self, x, order: int = 0):
        """``order=0``: MI (nats); ``order=1``: (MI, gradient (6,)) in nats per LU and per LU/TU."""
        order = validation.integer(order, "order", minimum=0, maximum=1)
        if order == 0:
            lin = self.inner.linearization(x)
            return self._kernel.value(lin.F, lin.H, row_scale=info_mod.range_noise_scale(lin, self.range_scale))
        lin = self.inner.linearization(x, derivatives=True)
        s, ds = info_mod.range_noise_scale(lin, self.range_scale, derivatives=True)
        value, grad = self._kernel.value_gradient(lin.F, lin.H, lin.dF, lin.dH, row_scale=s, d_row_scale=ds)
        return float(value), grad


class RegularisedJacobianInformation(_RemedyInformation):
    r"""The MI of a :class:`~cislunar.papers.wolf_jones.scenarios.WindowInformation` window whose range-rate
    Jacobians are regularised at short range (:func:`cislunar.sensing.information.regularised_range_rate_jacobian`):
    the position part :math:`(\Delta\dot{\mathbf r}-\dot\rho\hat\rho)^T/\rho` becomes
    :math:`(\Delta\dot{\mathbf r}-\dot\rho\hat\rho)^T/\sqrt{\rho^2+\rho_c^2}`; the noise, the range row and the
    velocity part are the paper's.

    Unlike :class:`RangeNoiseInformation`, which makes every measurement of a close target worth less, this remedy
    removes only the :math:`1/\rho` growth of the range-rate row, the one term the diagnosis blames: if it alone
    lets SCvx converge without a keep-out, that term is what fails.  Same protocol and parameters as
    :class:`RangeNoiseInformation` (``range_scale_km`` is :math:`\rho_c`, km); exact gradient (the product rule
    through the regularising factor).
    """

    #: The remedy's name in :func:`remedy_runs` and its tables.
    name = "regularised J"

    def __call__(self, x, order: int = 0):
        """``order=0``: MI (nats); ``order=1``: (MI, gradient (6,)) in nats per LU and per LU/TU."""
        order = validation.integer(order, "order", minimum=0, maximum=1)
        if order == 0:
            lin = self.inner.linearization(x)
            return self._kernel.value(lin.F, info_mod.regularised_range_rate_jacobian(lin, self.range_scale))
        lin = self.inner.linearization(x, derivatives=True)
        H, dH = info_mod.regularised_range_rate_jacobian(lin, self.range_scale, derivatives=True)
        value, grad = self._kernel.value_gradient(lin.F, H, lin.dF, dH)
        return float(value), grad


#: The remedies :func:`remedy_runs` can solve with, by name.
REMEDIES = {c.name: c for c in (RangeNoiseInformation, RegularisedJacobianInformation)}


# --------------------------------------------------------------------------------------------------------------
# passes at a chosen distance
# --------------------------------------------------------------------------------------------------------------
def passing_state(system, t_pass, r_target, d_km: float, x0, *, iterations: int = 8) -> np.ndarray:
    """Window-start state (6,) near ``x0`` whose ballistic arc is at ``d_km`` from ``r_target`` (3,) at ``t_pass``.

    ``t_pass = (t0, t1)``: window start and pass time, TU.  Newton on the position block of the STM, only the
    initial position moved, the goal on the line from the target to where ``x0`` itself arrives.
    """
    t2 = validation.as_array(t_pass, "t_pass", shape=(2,))
    r_tgt = validation.as_array(r_target, "r_target", shape=(3,))
    d = validation.positive(d_km, "d_km")
    x = validation.as_state(x0, "x0", batch=False).copy()
    iterations = validation.integer(iterations, "iterations", minimum=1)
    r_now = propagate(system, x, t2).x[-1, :3]
    goal = r_tgt + system.km_to_lu(d) * (r_now - r_tgt) / np.linalg.norm(r_now - r_tgt)
    for _ in range(iterations):
        tr = propagate_stm(system, x, t2)
        x[:3] += np.linalg.solve(tr.stm[-1][:3, :3], goal - tr.x[-1, :3])
    return x


def _closest(lin):
    """(target index, time index, range LU) of the closest approach in a window linearisation."""
    rho = np.linalg.norm(lin.observer[None, :, :3] - lin.targets[:, :, :3], axis=-1)
    j, k = np.unravel_index(np.argmin(rho), rho.shape)
    return int(j), int(k), float(rho[j, k])


def _whitened_jacobian(lin, j: int, k: int) -> np.ndarray:
    """(m, 6) whitened Jacobian of target ``j``'s measurements at time ``k`` with respect to the observer's state."""
    m = lin.H.shape[1] // lin.targets.shape[0]
    rows = slice(j * m, (j + 1) * m)
    L = np.linalg.cholesky(lin.R[k][rows, rows])
    return np.linalg.solve(L, lin.H[k][rows, 0:6])


@dataclass(frozen=True)
class PassScan:
    """Along passes of the target nearest the ballistic arc at ``d_km``: MI (nats), its gradient's position and
    velocity norms (nats/LU, nats/(LU/TU)), the largest absolute eigenvalue of its Hessian (nats per unit^2; NaN when not
    computed), and at the pass the whitened Jacobian's row norms (range, range-rate; per LU of relative position)
    and condition number (largest over smallest singular value)."""

    d_km: np.ndarray
    mi: np.ndarray
    grad_position: np.ndarray
    grad_velocity: np.ndarray
    hessian_norm: np.ndarray
    range_row: np.ndarray
    range_rate_row: np.ndarray
    jacobian_cond: np.ndarray

    def slope(self, name: str, below_km: float = 10.0) -> float:
        """Log-log slope of column ``name`` against the pass distance, over the passes closer than ``below_km``."""
        y = np.asarray(getattr(self, validation.choice(name, "name", (
            "mi", "grad_position", "grad_velocity", "hessian_norm", "range_row", "range_rate_row",
            "jacobian_cond"))), dtype=float)
        sel = (self.d_km < below_km) & np.isfinite(y) & (y > 0)
        if sel.sum() < 2:
            return float("nan")
        return float(np.polyfit(np.log(self.d_km[sel]), np.log(y[sel]), 1)[0])


def pass_scan(sc: wj.Scenario, info, x_ws, d_km, *, hessian: bool = False) -> PassScan:
    """Pass the target nearest the ballistic arc (at its closest measurement) at each distance of ``d_km``.

    Parameters
    ----------
    sc : Scenario
        Test case 2.
    info : WindowInformation, RangeNoiseInformation or RegularisedJacobianInformation
        The MI (value, gradient, and with ``hessian`` its Hessian).
    x_ws : array_like (6,)
        Ballistic window-start state.
    d_km : array_like
        Pass distances, km (> 0).
    hessian : bool
        Also the largest absolute eigenvalue of the MI Hessian (12 gradients per distance).
    """
    validation.instance(sc, "sc", wj.Scenario)
    validation.callable_(info, "info")
    x_ws = validation.as_state(x_ws, "x_ws", batch=False)
    d = validation.as_array(d_km, "d_km", ndim=(1,), min_size=1)
    if np.any(d <= 0):
        raise ValueError(f"d_km must be positive distances; got {d}")
    hessian = validation.boolean(hessian, "hessian")
    base = info.inner if isinstance(info, _RemedyInformation) else info
    lin0 = base.linearization(x_ws)
    j, k, _ = _closest(lin0)
    em = sc.system
    t2 = np.array([lin0.t[0], lin0.t[k]])
    r_tgt = lin0.targets[j, k, :3]
    cols = {n: [] for n in ("mi", "gp", "gv", "hn", "rr", "rrr", "cond")}
    for d_ in d:
        x = passing_state(em, t2, r_tgt, float(d_), x_ws)
        value, g = info(x, 1)
        cols["mi"].append(value)
        cols["gp"].append(np.linalg.norm(g[:3]))
        cols["gv"].append(np.linalg.norm(g[3:]))
        cols["hn"].append(float(np.max(np.abs(np.linalg.eigvalsh(info.hessian(x))))) if hessian else np.nan)
        J = _whitened_jacobian(base.linearization(x), j, k)
        cols["rr"].append(np.linalg.norm(J[0, :3]))
        cols["rrr"].append(np.linalg.norm(J[1, :3]))
        sv = np.linalg.svd(J, compute_uv=False)
        cols["cond"].append(sv[0] / sv[-1])
    return PassScan(d, *(np.array(cols[n]) for n in ("mi", "gp", "gv", "hn", "rr", "rrr", "cond")))


def brief_outcome(outcome: str) -> str:
    """An SCvx outcome without the solver's advice: cvxpy's "Try another solver, or solve with verbose=True ..."
    dropped, whole numbers kept (a failure reason cut at a fixed width could end inside a number)."""
    outcome = validation.instance(outcome, "outcome", str)
    return re.sub(r"\s*Try another solver[^.]*\.", "", outcome).strip()


# --------------------------------------------------------------------------------------------------------------
# the free run, diagnosed
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FreeRunDiagnosis:
    r"""SCvx on test case 2 without a keep-out, each reference diagnosed.

    Attributes
    ----------
    outcome : str
        "converged (...)" or the :class:`~cislunar.guidance.scvx.SCvxError` reason.
    status : str
        The convex solver's status at the failure as cvxpy reports it ("" if none failed).
    iterations : int
    ref_range_km : ndarray
        Closest approach to any target at a measurement, per reference, km.
    grad_position : ndarray
        Position part of the MI gradient per reference, nats/LU.
    hessian_norm : ndarray
        Largest absolute eigenvalue of the MI Hessian per reference (the last ``n_hessian`` references; NaN before),
        nats per unit^2.
    information_scale : ndarray
        Ratio of the information term's largest subproblem coefficient, :math:`\alpha_h\max(|g|, \|H\|)`, to the
        largest impulse weight :math:`(1-\alpha_h)\Delta t/2`, per reference: how far apart the scales that the
        convex solver must resolve are.
    last_eta : float
        Trust-region radius at the last iteration.
    history : list
    """

    outcome: str
    status: str
    iterations: int
    ref_range_km: np.ndarray
    grad_position: np.ndarray
    hessian_norm: np.ndarray
    information_scale: np.ndarray
    last_eta: float
    history: list

    @property
    def failed(self) -> bool:
        return not self.outcome.startswith("converged")

    def summary(self) -> str:
        n = self.ref_range_km.size
        show = sorted(set([0, n // 2] + list(range(max(n - 4, 0), n))))
        lines = [f"without keep-out: {self.outcome}" + (f" (solver status: {self.status})" if self.status else ""),
                 f"{'ref':>4} {'closest km':>11} {'|dI/dr| nats/LU':>16} {'|Hess| max':>11} {'info/impulse scale':>19}"]
        lines += [f"{i:4d} {self.ref_range_km[i]:11.3g} {self.grad_position[i]:16.3g} {self.hessian_norm[i]:11.3g} "
                  f"{self.information_scale[i]:19.3g}" for i in show]
        return "\n".join(lines)


_STATUS = re.compile(r"convex subproblem (\S+) at iteration")


def free_run_diagnosis(sc: wj.Scenario, t, k_ws: int, info, alpha: float, x_guess, u_guess, max_iter: int, *,
                       n_hessian: int = 3, settings: scvx.SCvxSettings | None = None) -> FreeRunDiagnosis:
    """Solve ``alpha`` without any keep-out (default settings with ``max_iter``), record and diagnose every
    reference (the MI Hessian at the last ``n_hessian`` references only: 12 gradients each)."""
    validation.instance(sc, "sc", wj.Scenario)
    t = validation.time_grid(t, "t", increasing=True)
    k_ws = validation.integer(k_ws, "k_ws", minimum=1, maximum=t.size - 2)
    validation.callable_(info, "info")
    alpha = validation.in_range(alpha, "alpha", 0.0, 1.0)
    max_iter = validation.integer(max_iter, "max_iter", minimum=1)
    n_hessian = validation.integer(n_hessian, "n_hessian", minimum=0)
    st = scvx.SCvxSettings(max_iter=max_iter) if settings is None else validation.instance(
        settings, "settings", scvx.SCvxSettings)
    rec = studies.RecordingInformation(info)
    solver = wj.ScenarioSolver(sc, t, k_ws, information=rec, keep_out=False, settings=st)
    try:
        res = solver(alpha, x_guess, u_guess)
        outcome, status, hist = f"converged ({res.iterations} iterations)", "", res.history
    except scvx.SCvxError as exc:
        hist, outcome = exc.history, exc.reason
        m = _STATUS.search(exc.reason)
        status = m.group(1) if m else ("solver error" if "failed" in exc.reason else "")
    refs = list(rec.refs)
    base = info.inner if isinstance(info, _RemedyInformation) else info
    em = sc.system
    ko = sc.keep_out(k_ws)
    ranges = np.array([ko.ranges(x).min() for x in refs]) * em.length_unit_km
    grads = [np.asarray(info(x, 1)[1]) for x in refs]
    gpos = np.array([np.linalg.norm(g[:3]) for g in grads])
    hn = np.full(len(refs), np.nan)
    for i in range(max(len(refs) - n_hessian, 0), len(refs)):
        hn[i] = float(np.max(np.abs(np.linalg.eigvalsh(info.hessian(refs[i])))))
    dt_max = float(np.max(np.diff(t)))
    weight = max((1.0 - alpha) * dt_max / 2.0, 1e-300)
    scale = np.array([alpha * max(np.max(np.abs(g)), 0.0 if np.isnan(h) else h) for g, h in zip(grads, hn)]) / weight
    del base
    return FreeRunDiagnosis(outcome, status, len(hist), ranges, gpos, hn, scale,
                            float(hist[-1]["eta"]) if hist else float("nan"), hist)


# --------------------------------------------------------------------------------------------------------------
# the remedy over the weights
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RemedyRun:
    r"""Test case 2 at one weight with a remedy and no keep-out (or with the keep-out and the paper's model).

    ``model``: "range noise" or "regularised J" (a remedy of :data:`REMEDIES`, no keep-out) or "keep-out" (the
    paper's model with the scenario's keep-out); ``converged``, ``outcome``; ``dv_mps`` impulse (m/s); ``mi`` the
    plan's MI under the paper's model (the plain window MI, nats) and ``mi_remedy`` under the run's remedy (the
    keep-out run: the first remedy solved); ``closest_km`` its closest approach to a
    target at a measurement; ``rms_km`` the observer's CRLB position RMS at the window end (km); ``cost`` the
    paper's objective :math:`(1-\alpha_h)\,\mathrm{impulse} - \alpha_h\mathcal I` with the paper's MI
    (non-dimensional: the plans of both models judged by one yardstick); ``result`` the
    :class:`~cislunar.guidance.scvx.SCvxResult` (None on failure).
    """

    model: str
    alpha: float
    converged: bool
    outcome: str
    iterations: int
    dv_mps: float
    mi: float
    mi_remedy: float
    closest_km: float
    rms_km: float
    cost: float
    result: object


def remedy_runs(sc: wj.Scenario, t, k_ws: int, info, range_scale_km: float, alphas, x_guess, u_guess, *,
                max_iter: int = 150, keep_out: bool = True, remedies=("range noise",)) -> list:
    """Solve each weight of ``alphas`` from the ballistic guess with each remedy of ``remedies`` (names of
    :data:`REMEDIES`: ``"range noise"``, :class:`RangeNoiseInformation`; ``"regularised J"``,
    :class:`RegularisedJacobianInformation`; both with :math:`\\rho_c` = ``range_scale_km``) and no keep-out
    (default SCvx settings with ``max_iter``) and, with ``keep_out``, with the paper's model and the scenario's
    keep-out from the same guess (cold starts all: a like-for-like comparison); a list of :class:`RemedyRun`, per
    weight in the order of ``remedies`` (then the keep-out run)."""
    validation.instance(sc, "sc", wj.Scenario)
    t = validation.time_grid(t, "t", increasing=True)
    k_ws = validation.integer(k_ws, "k_ws", minimum=1, maximum=t.size - 2)
    validation.instance(info, "info", wj.WindowInformation)
    a = validation.as_array(alphas, "alphas", ndim=(1,), min_size=1)
    max_iter = validation.integer(max_iter, "max_iter", minimum=1)
    keep_out = validation.boolean(keep_out, "keep_out")
    names = remedies if isinstance(remedies, (list, tuple)) else None
    if not names or any(n not in REMEDIES for n in names) or len(set(names)) != len(names):
        raise ValueError(f"remedies must be a non-empty sequence of distinct names from {tuple(REMEDIES)}; got "
                         f"{remedies!r}")
    models = {n: REMEDIES[n](info, range_scale_km) for n in names}
    st = scvx.SCvxSettings(max_iter=max_iter)
    solvers = [(n, m, wj.ScenarioSolver(sc, t, k_ws, information=m, keep_out=False, settings=st))
               for n, m in models.items()]
    if keep_out:  # its mi_remedy: under the first remedy
        solvers.append(("keep-out", models[names[0]],
                        wj.ScenarioSolver(sc, t, k_ws, information=info, keep_out=True, settings=st)))
    ko = sc.keep_out(k_ws)
    em = sc.system
    mps = em.velocity_unit_km_s * 1e3
    out = []
    for alpha in a:
        for model, remedy, solver in solvers:
            try:
                r = solver(float(alpha), x_guess, u_guess)
            except scvx.SCvxError as exc:
                out.append(RemedyRun(model, float(alpha), False, exc.reason, len(exc.history), np.nan, np.nan, np.nan,
                                     np.nan, np.nan, np.nan, None))
                continue
            xw = r.x[k_ws]
            mi = float(info(xw, 0))
            out.append(RemedyRun(model, float(alpha), True, f"{r.stopped_by} stop after {r.iterations} iterations",
                                 r.iterations, r.impulse * mps, mi, float(remedy(xw, 0)),
                                 float(ko.ranges(xw).min() * em.length_unit_km),
                                 float(wj.evaluate_crlb(sc, xw).terminal_rms_km[0]),
                                 float((1.0 - alpha) * r.impulse - alpha * mi), r))
    return out


def remedy_table(runs) -> str:
    """The runs of :func:`remedy_runs` as text, one line per run."""
    if not isinstance(runs, (list, tuple)):
        raise validation.ArgumentTypeError(f"runs must be a list of RemedyRun; got {type(runs).__name__}")
    lines = [f"{'alpha_h':>8} {'model':>12} {'ok':>3} {'iter':>5} {'dV m/s':>8} {'MI':>8} {'MI remedy':>10} "
             f"{'closest km':>11} {'RMS km':>8} {'paper cost':>11}"]
    for r in runs:
        validation.instance(r, "runs[i]", RemedyRun)
        lines.append(f"{r.alpha:8.4f} {r.model:>12} {'y' if r.converged else 'n':>3} {r.iterations:5d} "
                     f"{r.dv_mps:8.2f} {r.mi:8.3f} {r.mi_remedy:10.3f} {r.closest_km:11.1f} {r.rms_km:8.2f} {r.cost:11.6f}"
                     + ("" if r.converged else f"  ({brief_outcome(r.outcome)})"))
    return "\n".join(lines)

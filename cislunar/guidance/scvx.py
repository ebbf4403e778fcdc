r"""Successive convexification (SCvx) with first-order hold for a low-thrust observer (Wolf & Jones, §SCvx).

The problem
-----------
Find node states :math:`x_k` and first-order-hold accelerations :math:`u_k` (:mod:`cislunar.guidance.discretization`) that
minimise the nonlinear cost (Eq. 42 with the homotopy of Eq. 24)

.. math:: \mathcal J = (1-\alpha_h)\sum_k\tfrac{\Delta t_k}{2}(\|u_k\|+\|u_{k+1}\|) - \alpha_h\,\mathcal I(x_{k^*})
          + \mathcal P(\delta),

where :math:`\mathcal I` is the mutual information of the observation window that starts at node :math:`k^*`
(the thrust is zero inside the window, so the window's measurements depend on :math:`x_{k^*}` only),
:math:`\delta_k = x_{k+1} - f_k(x_k, u_k, u_{k+1})` are the multiple-shooting defects (Eq. 34) and
:math:`\mathcal P` penalises them.  Each iteration solves the convex subproblem (Eq. 30)

.. math:: \min\ (1-\alpha_h)\,\mathrm{impulse}(u) - \alpha_h\,\hat{\mathcal I}(x_{k^*}) + \hat{\mathcal P}(\nu)
   \quad\text{s.t.}\ x_{k+1} = A_kx_k + B_k^-u_k + B_k^+u_{k+1} + r_k + \nu_k,\ x_0 = x_{ic},\ x_{N-1} = x_{tc},
   \ \|u_k\|\le u_{max,k},\ \|x_k-\bar x_k\| + \|u_k-\bar u_k\|\le\eta,

with the virtual control :math:`\nu_k` standing in for the defect, and accepts or rejects the step with the
ratio :math:`\rho` of actual to predicted decrease (Eq. 36, Table 1).

What makes it converge (documented departures from the printed method)
-----------------------------------------------------------------------
* **Augmented Lagrangian on the defects** (SCvx*, Oguri 2023), ``method="augmented_lagrangian"`` (default):
  :math:`\mathcal P(\delta) = \sum_k\lambda_k^\top\delta_k + \tfrac w2\|\delta_k\|^2`; after an accepted step
  whose cost change is below a threshold :math:`\varepsilon_\lambda`, the multipliers are updated,
  :math:`\lambda\leftarrow\lambda + w\delta`, the weight grows :math:`w\leftarrow\min(\beta w, w_{max})` and the
  threshold shrinks.  The paper's L1 exact penalty :math:`\gamma\sum_k\Delta t_k\|\nu_k\|_1` stays available as
  ``method="penalty"``; with a linear reward it creeps (every step sits on the trust-region boundary and the
  second-order defects of a step of size :math:`\eta` eat the predicted gain), and on test case 1 it still
  creeps with the quadratic information model (notebook 05: rho ~ 0.1-0.2, eta ~ 1e-3 after 80 iterations).
* **Convex quadratic information model**: :math:`\hat{\mathcal I}(x) = \mathcal I_0 + g^\top dx +
  \tfrac12 dx^\top H_-dx`, with :math:`H_-` the concave part of the Hessian (eigenvalues clipped to
  :math:`\le 0`), so :math:`-\alpha_h\hat{\mathcal I}` is convex and the subproblem has an interior minimum.  The
  Hessian comes from the model's ``hessian`` method or forward differences of its gradient, refreshed when
  the window-start state has moved by more than ``hessian_refresh`` or when the information part of the model
  error was large (``hessian_error_ratio``).
  ``information_model="linear"`` gives the paper's Eq. 44.
* A predicted decrease at the noise level of the subproblem solution counts as :math:`\rho = 1`; Clarabel runs
  with tight tolerances; the iteration stops only on an accepted step with defects below ``defect_tol``, a
  cost change below ``tol`` and an inactive trust region.  A trust region that shrinks below ``eta_min`` raises
  :class:`SCvxError` (never a success).  ``solve_scvx(..., practical_stop=PracticalStop(...))`` adds a practical
  rule (off by default): stop after a few consecutive accepted steps with closed defects and a small cost change,
  the trust region active or not (the paper prints no stopping test).

The information model protocol
------------------------------
``info(x, order)`` with ``x`` the observer state (6,) at node ``info_node``: ``order=0`` returns the value
(nats), ``order=1`` returns ``(value, gradient)``; value and gradient must describe the same function (e.g. the
process noise held fixed).  SCvx takes every value from ``order=0`` and only the gradient from ``order=1`` (a
value computed alongside a gradient may carry different round-off).  An optional ``info.hessian(x)`` returns the
(6, 6) Hessian.
:class:`cislunar.papers.wolf_jones.scenarios.WindowInformation` implements it for the paper's test cases.

Cost of a run
-------------
The subproblem is built once per structure with cvxpy Parameters (DPP; the FOH model of every interval in one
stacked Parameter) and re-solved with new values; :class:`SCvxWorkspace` keeps it between runs, so a homotopy sweep
canonicalises once (bit-for-bit the solutions of fresh problems).  With Clarabel, each solve hands cvxpy's
canonical data (the cached parameter program applied to the current values) straight to the solver and copies the
solution into the variables, the steps of cvxpy's warm re-solve without ``Problem.solve``'s bookkeeping (bit for
bit the same; a test compares the two paths).  The gradient and Hessian at a new reference are computed only when
the iteration goes on (not on the converged step).

Extra nonconvex inequality constraints (e.g. a keep-out) are objects with ``node``, ``size`` and
``__call__(x) -> (c, C)`` (values that must be :math:`\le 0` and their Jacobian with respect to the state at
``node``); they are linearised with a non-negative slack that is penalised like the defects.
"""

from __future__ import annotations

import threading
import time
import warnings
from dataclasses import dataclass, field, fields

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.cr3bp.propagation import DEFAULT_TOL, ImpactError, _inside_primaries
from cislunar.guidance.discretization import _check_outside, _foh_discretize
from cislunar.utils import validation
from cislunar.utils.progress import progress as _progress

__all__ = ["SCvxSettings", "PracticalStop", "SCvxResult", "SCvxError", "SCvxWorkspace", "solve_scvx", "concave_part", "finite_difference_hessian",
           "SweepResult", "homotopy_sweep", "impulse"]

METHODS = ("augmented_lagrangian", "penalty")
INFORMATION_MODELS = ("quadratic", "linear")


class SCvxError(RuntimeError):
    """SCvx failed (subproblem infeasible, trust-region collapse or no convergence); carries the history.

    Attributes
    ----------
    reason : str
        What went wrong.
    history : list of dict
        The per-iteration log (see :class:`SCvxResult`).
    """

    def __init__(self, reason: str, history=None):
        self.reason = str(reason)
        self.history = list(history or [])
        tail = [{k: h[k] for k in ("iteration", "cost", "rho", "eta", "accepted", "max_defect") if k in h}
                for h in self.history[-3:]]
        super().__init__(f"{self.reason}; last iterations: {tail}")

    def __reduce__(self):
        return (type(self), (self.reason, self.history))


@dataclass(frozen=True)
class SCvxSettings:
    """Settings of the SCvx iteration (every field is validated; errors name the field).

    Attributes
    ----------
    method : {"augmented_lagrangian", "penalty"}
        Defect handling: SCvx* augmented Lagrangian (default) or the paper's L1 exact penalty.
    information_model : {"quadratic", "linear"}
        Convex quadratic model from the concave part of the Hessian (default) or the linear model of Eq. 44.
    rho0, rho1, rho2 : float
        Acceptance thresholds of Table 1 (0 <= rho0 < rho1 < rho2 <= 1).
    beta_shrink, beta_grow : float
        Trust-region shrink and growth factors (> 1).
    eta0, eta_min, eta_max : float
        Initial, smallest and largest trust-region radius (non-dimensional), 0 < eta_min <= eta0 <= eta_max.
    defect_weight : float
        :math:`\\gamma` of the exact penalty (``method="penalty"``; > 0).
    penalty_weight0, penalty_weight_max : float
        Initial and largest augmented-Lagrangian weight :math:`w` (> 0).
    penalty_growth : float
        Factor :math:`\\beta \\ge 1` applied to :math:`w` at each multiplier update.
    multiplier_threshold0 : float
        Initial relative cost change :math:`\\varepsilon_\\lambda` below which the multipliers are updated (> 0).
    multiplier_threshold_decay : float
        Factor in (0, 1] applied to :math:`\\varepsilon_\\lambda` at each multiplier update.
    max_iter : int
        Largest number of iterations (>= 1).
    tol : float
        Stop when an accepted step changes the cost by less than ``tol (1 + |J|)`` (> 0) ...
    defect_tol : float
        ... the largest defect norm (LU, LU/TU) and constraint violation are below ``defect_tol`` (> 0) ...
    active_tol : float
        ... and the step is shorter than ``(1 - active_tol) eta`` (the trust region is inactive; in (0, 1)).
    noise_tol : float
        A predicted decrease below ``noise_tol (1 + |J|)`` is at the subproblem's noise level and counts as
        rho = 1 (>= 0).
    solver_tol : float
        Clarabel gap and feasibility tolerances (> 0).
    hessian_step : float
        Central-difference step for the information Hessian, relative to ``1 + |x|`` (> 0).
    hessian_refresh : float
        The Hessian is recomputed after an accepted step only when the window-start state has moved by more than
        this (2-norm, non-dimensional; >= 0, 0 = every accepted step) since it was last computed.  A stale
        curvature only regularises the step: value and gradient are always current, and the ratio test
        judges the model.
    hessian_error_ratio : float
        ... or when the information part of the last model error exceeded this fraction of the predicted
        decrease (> 0; an accepted step refreshes at the new point, a rejected one at the reference).
    stall_iter : int
        Raise :class:`SCvxError` ("stalled") when this many consecutive iterations bring no progress: no accepted
        step lowering the cost by more than ``10 noise_tol (1 + |J|)``, no multiplier update and no halving of the
        largest defect (0 disables; saves the remaining iterations of a run that grinds at the noise floor).
    curvature_floor : float
        Smallest concave curvature of the information model, relative to the largest Hessian eigenvalue
        magnitude (:func:`concave_part`; >= 0).
    """

    method: str = "augmented_lagrangian"
    information_model: str = "quadratic"
    rho0: float = 0.0
    rho1: float = 0.1
    rho2: float = 0.7
    beta_shrink: float = 2.0
    beta_grow: float = 2.0
    eta0: float = 0.05
    eta_min: float = 1e-8
    eta_max: float = 0.1
    defect_weight: float = 1e3
    penalty_weight0: float = 1e3
    penalty_weight_max: float = 1e7
    penalty_growth: float = 3.0
    multiplier_threshold0: float = 1e-3
    multiplier_threshold_decay: float = 0.3
    max_iter: int = 150
    tol: float = 1e-8
    defect_tol: float = 5e-10
    active_tol: float = 1e-3
    noise_tol: float = 1e-9
    solver_tol: float = 1e-10
    hessian_step: float = 1e-5
    hessian_refresh: float = 5e-3
    hessian_error_ratio: float = 0.3
    stall_iter: int = 60
    curvature_floor: float = 0.0

    def __post_init__(self):
        validation.choice(self.method, "method", METHODS)
        validation.choice(self.information_model, "information_model", INFORMATION_MODELS)
        for f in fields(self):
            if f.name in ("method", "information_model"):
                continue
            if f.name in ("max_iter", "stall_iter"):
                validation.integer(getattr(self, f.name), f.name, minimum=1 if f.name == "max_iter" else 0)
                continue
            validation.real(getattr(self, f.name), f.name)
        for name in ("rho0", "rho1", "rho2"):
            validation.in_range(getattr(self, name), name, 0.0, 1.0)
        if not self.rho0 < self.rho1 < self.rho2:
            raise ValueError(f"rho0, rho1, rho2 must satisfy rho0 < rho1 < rho2; got {self.rho0}, {self.rho1}, "
                             f"{self.rho2}")
        for name in ("beta_shrink", "beta_grow"):
            if not getattr(self, name) > 1.0:
                raise ValueError(f"{name} must be > 1; got {getattr(self, name)}")
        for name in ("eta0", "eta_min", "eta_max", "defect_weight", "penalty_weight0", "penalty_weight_max",
                     "multiplier_threshold0", "tol", "defect_tol", "solver_tol", "hessian_step"):
            validation.positive(getattr(self, name), name)
        validation.positive(self.noise_tol, "noise_tol", allow_zero=True)
        validation.positive(self.hessian_refresh, "hessian_refresh", allow_zero=True)
        validation.positive(self.curvature_floor, "curvature_floor", allow_zero=True)
        validation.positive(self.hessian_error_ratio, "hessian_error_ratio")
        if not self.eta_min <= self.eta0:
            raise ValueError(f"eta0 must be >= eta_min ({self.eta_min}); got {self.eta0}")
        if not self.eta0 <= self.eta_max:
            raise ValueError(f"eta_max must be >= eta0 ({self.eta0}); got {self.eta_max}")
        if not self.penalty_weight0 <= self.penalty_weight_max:
            raise ValueError(f"penalty_weight_max must be >= penalty_weight0 ({self.penalty_weight0}); got "
                             f"{self.penalty_weight_max}")
        if not self.penalty_growth >= 1.0:
            raise ValueError(f"penalty_growth must be >= 1; got {self.penalty_growth}")
        validation.in_range(self.multiplier_threshold_decay, "multiplier_threshold_decay", 0.0, 1.0)
        if self.multiplier_threshold_decay == 0.0:
            raise ValueError("multiplier_threshold_decay must be in (0, 1]; got 0")
        validation.in_range(self.active_tol, "active_tol", 0.0, 1.0, closed=False)


@dataclass(frozen=True)
class PracticalStop:
    """A practical stopping rule for :func:`solve_scvx` (keyword ``practical_stop``; default none: only the strict
    test of :class:`SCvxSettings` stops a run).

    The run also stops, as a success with ``SCvxResult.stopped_by == "practical"``, after ``window`` consecutive
    accepted steps that each end with the largest defect norm and constraint violation at most ``defect_tol`` and
    change both the merit function (objective plus defect penalty) and the objective by at most
    ``cost_tol (1 + |J|)``; rejected steps in between neither count nor reset the count.  Unlike the strict test it
    does not ask for an inactive trust region, which a linear information model (the paper's Eq. 44) pins to its
    boundary; it never stops with open defects.  The paper prints no stopping test.

    Attributes
    ----------
    window : int
        Consecutive qualifying accepted steps (>= 1).
    defect_tol : float
        Largest defect norm and violation allowed (LU, LU/TU; > 0).
    cost_tol : float
        Largest relative cost change per step allowed (> 0).
    """

    window: int = 5
    defect_tol: float = 1e-8
    cost_tol: float = 1e-8

    def __post_init__(self):
        validation.integer(self.window, "window", minimum=1)
        validation.positive(self.defect_tol, "defect_tol")
        validation.positive(self.cost_tol, "cost_tol")


@dataclass
class SCvxResult:
    """Converged SCvx solution.

    Attributes
    ----------
    t : ndarray (N,)
        Node times, TU.
    x : ndarray (N, 6)
        Node states (LU, LU/TU).
    u : ndarray (N, 3)
        Node accelerations (LU/TU^2), first-order hold in between.
    alpha : float
        Homotopy weight.
    cost : float
        Objective :math:`(1-\\alpha_h)\\,\\mathrm{impulse} - \\alpha_h\\mathcal I` at the solution (the defect
        penalty, below ``defect_tol``, excluded).
    impulse : float
        Trapezoid total impulse :math:`\\sum\\Delta t_k(\\|u_k\\|+\\|u_{k+1}\\|)/2`, LU/TU.
    information : float
        Mutual information of the window at the solution, nats (NaN without an information model).
    max_defect : float
        Largest multiple-shooting defect norm.
    history : list of dict
        Per iteration: ``iteration, cost, new_cost, predicted, actual, rho, eta, accepted, tr_active, step,
        max_defect, max_violation, model_error_defect, model_error_info, penalty_weight, multiplier_update,
        information, impulse, status`` and the times ``t_discretize, t_info, t_hessian, t_solve`` (seconds).
    stopped_by : {"strict", "practical"}
        Which stopping test ended the run (``"practical"``: :class:`PracticalStop`).
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    alpha: float
    cost: float
    impulse: float
    information: float
    max_defect: float
    history: list = field(default_factory=list)
    stopped_by: str = "strict"

    @property
    def iterations(self) -> int:
        return len(self.history)


def impulse(t, u) -> float:
    """Trapezoid total impulse of node accelerations ``u`` (N, 3) on node times ``t`` (N,), LU/TU."""
    t = validation.time_grid(t, "t", increasing=True)
    u = validation.as_array(u, "u", shape=(t.size, 3))
    return _impulse(np.diff(t), u)


def _impulse(dt, u) -> float:
    """Unchecked kernel of :func:`impulse` (``dt`` the node intervals (N-1,), ``u`` (N, 3))."""
    nrm = np.linalg.norm(u, axis=1)
    return float(np.sum(dt * (nrm[:-1] + nrm[1:]) / 2.0))


def concave_part(H, floor: float = 0.0) -> np.ndarray:
    """Factor ``L`` with ``-L L^T`` the concave (negative semi-definite) part of a symmetric matrix ``H``.

    Parameters
    ----------
    H : array_like (n, n)
    floor : float
        Every eigenvalue is clipped to at most ``-floor max|lambda|`` (0: the plain concave part; > 0 keeps a
        little concave curvature in the directions where ``H`` is convex or flat, so a model built on it has an
        interior maximum there too).

    Returns
    -------
    ndarray (n, n)
        ``L = V diag(sqrt(max(-lambda, floor max|lambda|)))`` from ``H = V diag(lambda) V^T``.
    """
    H = validation.square(H, "H")
    if H.size == 0:
        raise ValueError("H must be a non-empty square matrix; got shape (0, 0)")
    floor = validation.positive(floor, "floor", allow_zero=True)
    return _concave_part(H, floor)


def _concave_part(H, floor: float) -> np.ndarray:
    """Unchecked kernel of :func:`concave_part` (``H`` a finite square array, ``floor`` >= 0)."""
    lam, V = np.linalg.eigh(0.5 * (H + H.T))
    lo = floor * float(np.max(np.abs(lam))) if lam.size else 0.0
    return V * np.sqrt(np.maximum(-lam, lo))[None, :]


def finite_difference_hessian(gradient, x, step: float = 1e-5, *, g0=None) -> np.ndarray:
    """Symmetrised finite-difference Hessian of a scalar function from its gradient ``gradient(x) -> (n,)``.

    Central differences (2n gradient calls, error O(h^2)), or forward differences from the gradient ``g0`` at
    ``x`` when it is given (n calls, error O(h)).  The step of component ``i`` is ``step (1 + |x_i|)``.
    """
    validation.callable_(gradient, "gradient")
    x = validation.as_array(x, "x", ndim=(1,), min_size=1)
    step = validation.positive(step, "step")
    n = x.size
    if g0 is not None:
        g0 = validation.as_array(g0, "g0", shape=(n,))

    def grad(z):
        return validation.as_array(gradient(z), "gradient(x)", shape=(n,))

    H = np.empty((n, n))
    for i in range(n):
        h = step * (1.0 + abs(x[i]))
        e = np.zeros(n)
        e[i] = h
        if g0 is None:
            H[:, i] = (grad(x + e) - grad(x - e)) / (2.0 * h)
        else:
            H[:, i] = (grad(x + e) - g0) / h
    return 0.5 * (H + H.T)


class _Subproblem:
    """The convex subproblem, built once with cvxpy Parameters (DPP) and re-solved with new values."""

    def __init__(self, n: int, has_terminal: bool, k_star: int | None, con_specs, coast=None):
        import cvxpy as cp

        self.n = n
        self.x = cp.Variable((n, 6))
        self.u = cp.Variable((n, 3))
        self.nu = cp.Variable((n - 1, 6))
        # [A_k | B-_k | B+_k] of every interval stacked in one Parameter (rows 6k..6k+5): one value assignment per
        # iteration instead of 3 (N-1), the same canonicalised coefficients
        self.AB = cp.Parameter((6 * (n - 1), 12))
        self.r = cp.Parameter((n - 1, 6))
        self.xbar = cp.Parameter((n, 6))
        self.ubar = cp.Parameter((n, 3))
        self.eta = cp.Parameter(nonneg=True)
        self.umax = cp.Parameter(n, nonneg=True)
        self.x_ic = cp.Parameter(6)
        self.x_tc = cp.Parameter(6)
        self.w_u = cp.Parameter(n, nonneg=True)  # (1 - alpha) * trapezoid weights of the node control norms
        self.lam = cp.Parameter((n - 1, 6))  # augmented-Lagrangian multipliers of the defects
        self.half_w = cp.Parameter(nonneg=True)  # w / 2
        self.gamma_dt = cp.Parameter(n - 1, nonneg=True)  # exact-penalty weights gamma * dt_k
        cons = [self.x[0] == self.x_ic]
        if has_terminal:
            cons.append(self.x[n - 1] == self.x_tc)
        for k in range(n - 1):
            blk = self.AB[6 * k:6 * k + 6]
            cons.append(self.x[k + 1] == blk[:, 0:6] @ self.x[k] + blk[:, 6:9] @ self.u[k] + blk[:, 9:12] @ self.u[k + 1]
                        + self.r[k] + self.nu[k])
        unorm = cp.norm(self.u, 2, axis=1)
        cons.append(unorm <= self.umax)
        if coast is not None and np.any(coast):  # zero bound: exactly zero (not zero to solver precision)
            cons.append(self.u[np.flatnonzero(coast)] == 0)
        self.step = cp.norm(self.x - self.xbar, 2, axis=1) + cp.norm(self.u - self.ubar, 2, axis=1)
        cons.append(self.step <= self.eta)
        objective = (self.w_u @ unorm + cp.sum(cp.multiply(self.lam, self.nu)) + self.half_w * cp.sum_squares(self.nu)
                     + self.gamma_dt @ cp.norm(self.nu, 1, axis=1))
        self.k_star = k_star
        if k_star is not None:
            self.g = cp.Parameter(6)  # alpha * information gradient at node k_star
            self.L = cp.Parameter((6, 6))  # sqrt(alpha) * factor of the concave part of the Hessian
            self.dxs = cp.Variable(6)
            cons.append(self.dxs == self.x[k_star] - self.xbar[k_star])
            objective = objective - self.g @ self.dxs + 0.5 * cp.sum_squares(self.L.T @ self.dxs)
        self.con = []
        for node, m in con_specs:
            c = cp.Parameter(m)
            C = cp.Parameter((m, 6))
            mu = cp.Parameter(m)
            s = cp.Variable(m, nonneg=True)
            dx = cp.Variable(6)
            cons += [dx == self.x[node] - self.xbar[node], c + C @ dx <= s]
            gam = cp.Parameter(nonneg=True)
            objective = objective + mu @ s + self.half_w * cp.sum_squares(s) + gam * cp.sum(s)
            self.con.append(dict(c=c, C=C, mu=mu, s=s, gamma=gam, node=node))
        self.problem = cp.Problem(cp.Minimize(objective), cons)

    def set_model(self, model):
        """Load the FOH model's ``A``, ``Bm``, ``Bp`` (N-1, 6, {6, 3, 3}) and ``r`` (N-1, 6)."""
        self.AB.value = np.concatenate([model.A, model.Bm, model.Bp], axis=2).reshape(6 * (self.n - 1), 12)
        self.r.value = model.r

    def solve(self, solver: str, new: bool, opts: dict) -> str:
        """Solve with the current Parameter values; returns the cvxpy status (variable values set as by cvxpy).

        ``new``: start a new solver object (else the previous one is updated with the new data, as cvxpy's
        ``warm_start=True``).  For Clarabel, :meth:`_solve_clarabel` replays cvxpy's own re-solve steps (the same
        parameter application, the same matrices handed to the same Clarabel calls, the same solution entries
        copied into the variables) without the per-call bookkeeping of ``Problem.solve``; other solvers go
        through ``Problem.solve``.
        """
        if solver.upper() != "CLARABEL":
            self.problem.solve(solver=solver, warm_start=not new, **opts)
            return self.problem.status
        return self._solve_clarabel(new, opts)

    def _prepare_clarabel(self, opts):
        """Canonicalise (once per problem: cvxpy's DPP cache) and record, for each variable, which entries of the
        solver's primal vector cvxpy copies into it (found by inverting a solution whose entries are their own
        indices)."""
        from cvxpy.reductions.solvers.conic_solvers.clarabel_conif import CLARABEL, dims_to_solver_cones

        data, chain, inverse = self.problem.get_problem_data("CLARABEL", solver_opts=opts)
        nx = data["c"].size

        class _Probe:  # the attributes of a Clarabel solution that cvxpy's inversion reads
            status, x, z, obj_val, solve_time, iterations = "Solved", np.arange(nx, dtype=float), None, 0.0, 0.0, 0

        primal = chain.invert(_Probe(), inverse).primal_vars
        slices = []
        for v in self.problem.variables():
            val = np.asarray(primal[v.id])
            flat = val.ravel(order="F")
            a = int(flat[0]) if flat.size else 0
            if val.shape != v.shape or not np.array_equal(flat, np.arange(a, a + flat.size)):
                return None  # not a plain slice (a transformed variable): keep cvxpy's path
            slices.append((v, a, a + flat.size, v.shape))
        self._clarabel = dict(chain=chain, pp=self.problem._cache.param_prog, cones=dims_to_solver_cones(data["dims"]),
                              slices=slices, status_map=CLARABEL.STATUS_MAP, parse=CLARABEL.parse_solver_opts,
                              solver=None)
        return self._clarabel

    def _solve_clarabel(self, new: bool, opts: dict) -> str:
        """cvxpy's warm re-solve for Clarabel (cvxpy 1.9: ``Problem.get_problem_data`` on the cached parameter
        program, ``CLARABEL.solve_via_data``, ``Problem.unpack_results``), step by step, primal values only."""
        import clarabel
        import cvxpy as cp
        import scipy.sparse as sp
        from cvxpy import settings as cps

        fast = getattr(self, "_clarabel", None)
        if fast is None:
            fast = self._prepare_clarabel(opts)
            if fast is None:
                self._clarabel = False
        if not fast:
            self.problem.solve(solver="CLARABEL", warm_start=not new, **opts)
            return self.problem.status
        for reduction in fast["chain"].reductions:  # e.g. the nonneg Parameters' reduced copies
            reduction.update_parameters(self.problem)
        P, q, _, A, b = fast["pp"].apply_parameters(quad_obj=True)
        A = -A
        P = sp.triu(P).tocsc()
        solver = None if new else fast["solver"]
        if solver is not None:
            if not solver.is_data_update_allowed():
                solver = None
            else:
                try:
                    solver.update(P=P, q=q, A=A, b=b, settings=fast["parse"](False, opts, solver.get_settings()))
                except Exception:  # noqa: BLE001 - as cvxpy: a structure change needs a new solver
                    solver = None
        if solver is None:
            solver = clarabel.DefaultSolver(P, q, A, b, fast["cones"], fast["parse"](False, opts))
        fast["solver"] = solver
        res = solver.solve()
        status = fast["status_map"].get(str(res.status), cps.SOLVER_ERROR)
        if status in cps.ERROR:
            raise cp.error.SolverError("Solver 'CLARABEL' failed. Try another solver, or solve with verbose=True for "
                                       "more information.")
        x = np.asarray(res.x) if status in cps.SOLUTION_PRESENT else None
        for v, a, e, shape in fast["slices"]:
            v.save_value(None if x is None else x[a:e].reshape(shape, order="F"))
        return status


class SCvxWorkspace:
    """Convex subproblems of :func:`solve_scvx` kept between runs, so that a sweep canonicalises once.

    :func:`solve_scvx` builds its subproblem with cvxpy Parameters (DPP) and re-solves it with new values at every
    iteration; the first solve of a problem canonicalises it (the cost of 15-45 re-solves at 40 nodes).
    Passing one workspace to every run of a sweep (same node count, terminal constraint, window node, extra
    constraints and coast pattern) reuses the canonicalised problem across runs.  Every Parameter is assigned
    before each solve and the first solve of every run starts a new Clarabel solver (later ones update its data,
    as within a run on a new problem), so a run gives the same solution whether its problem is new or reused (a
    test checks it bit for bit).

    Problems are kept per thread (two threads never share one) and dropped when the workspace is pickled (a
    process builds its own).

    Parameters
    ----------
    max_problems : int
        Most problem structures kept (least recently used dropped first; >= 1).
    """

    def __init__(self, max_problems: int = 4):
        self.max_problems = validation.integer(max_problems, "max_problems", minimum=1)
        self._problems: dict = {}
        self.builds = 0  # problems built (canonicalised) so far

    def __getstate__(self):
        return {"max_problems": self.max_problems, "_problems": {}, "builds": 0}

    def _subproblem(self, n, has_terminal, k_star, con_specs, coast) -> "_Subproblem":
        key = (threading.get_ident(), n, has_terminal, k_star, tuple(con_specs), np.asarray(coast).tobytes())
        sub = self._problems.pop(key, None)
        if sub is None:
            sub = _Subproblem(n, has_terminal, k_star, con_specs, coast=coast)
            self.builds += 1
        self._problems[key] = sub  # most recently used last
        while len(self._problems) > self.max_problems:
            self._problems.pop(next(iter(self._problems)))
        return sub


def _check_constraint(obj, i, n):
    name = f"constraints[{i}]"
    if not callable(obj):
        raise validation.ArgumentTypeError(f"{name} must be callable (x) -> (c, C); got {type(obj).__name__}")
    for attr in ("node", "size"):
        if not hasattr(obj, attr):
            raise validation.ArgumentTypeError(f"{name} must have a '{attr}' attribute")
    node = validation.integer(obj.node, f"{name}.node", minimum=0, maximum=n - 1)
    size = validation.integer(obj.size, f"{name}.size", minimum=1)
    return node, size


def solve_scvx(system: CR3BP, t_nodes, x_guess, u_guess, u_max, *, x_final=None, info=None, info_node=None,
               constraints=(), alpha: float = 0.0, settings: SCvxSettings | None = None, solver: str = "CLARABEL",
               progress: bool = False, workspace: SCvxWorkspace | None = None,
               practical_stop: PracticalStop | None = None) -> SCvxResult:
    """Solve the observer trajectory problem by SCvx (see the module docstring for the algorithm).

    Parameters
    ----------
    system : CR3BP
    t_nodes : array_like, shape (N,)
        Strictly increasing node times (e.g. Sundman-spaced), TU.
    x_guess, u_guess : array_like, shapes (N, 6), (N, 3)
        Initial reference; ``x_guess[0]`` is the fixed initial state, the last node is replaced by ``x_final``
        when given (the mismatch shows up as defects, which the iteration removes); guess controls above
        ``u_max`` are scaled down onto the bound.
    u_max : array_like, shape (N,)
        Bound on each node's acceleration norm, LU/TU^2 (zero at the nodes of observation windows).
    x_final : array_like, shape (6,), optional
        Terminal state constraint (Eq. 30d).
    info : callable, optional
        Information model ``info(x, order)`` of the observer state at node ``info_node`` (module docstring).
    info_node : int, optional
        Index of the window-start node; required with ``info``.
    constraints : sequence, optional
        Extra nonconvex inequality constraints (module docstring).
    alpha : float
        Homotopy weight :math:`\\alpha_h` in [0, 1].
    settings : SCvxSettings, optional
    solver : str
        cvxpy solver name (the tolerances of ``settings.solver_tol`` are passed to Clarabel only).
    progress : bool
        Progress bar over the iterations (:func:`cislunar.utils.progress.progress`).
    workspace : SCvxWorkspace, optional
        Keeps the canonicalised convex subproblem for the next run with the same structure (a sweep passes one
        workspace to all its runs); default: a subproblem built for this run only.
    practical_stop : PracticalStop, optional
        A practical stopping rule besides the strict test (default none: results bit-for-bit those without it).

    Returns
    -------
    SCvxResult

    Raises
    ------
    SCvxError
        Subproblem infeasible or failed, trust region collapsed (eta < eta_min), or no convergence within
        ``max_iter``; carries the per-iteration history.
    TypeError, ValueError
        Bad arguments (the message names the argument).
    """
    import cvxpy as cp

    check_system(system, "system")
    if settings is None:
        settings = SCvxSettings()
    st = validation.instance(settings, "settings", SCvxSettings)
    t = validation.time_grid(t_nodes, "t_nodes", increasing=True)
    n = t.size
    x_ref = validation.as_array(x_guess, "x_guess", shape=(n, 6)).copy()
    _check_outside(system, x_ref, "x_guess")
    u_ref = validation.as_array(u_guess, "u_guess", shape=(n, 3)).copy()
    umax = validation.as_array(u_max, "u_max", shape=(n,))
    if np.any(umax < 0):
        raise ValueError("u_max must be non-negative")
    alpha = validation.in_range(alpha, "alpha", 0.0, 1.0)
    if info is not None:
        validation.callable_(info, "info")
        if info_node is None:
            raise ValueError("info_node must be given with info (index of the window-start node)")
        info_node = validation.integer(info_node, "info_node", minimum=0, maximum=n - 1)
    elif info_node is not None:
        info_node = validation.integer(info_node, "info_node", minimum=0, maximum=n - 1)
    if constraints is None:
        constraints = ()
    if not isinstance(constraints, (list, tuple)):
        raise validation.ArgumentTypeError(f"constraints must be a list or tuple; got {type(constraints).__name__}")
    con_specs = [_check_constraint(c, i, n) for i, c in enumerate(constraints)]
    validation.boolean(progress, "progress")
    if workspace is not None:
        validation.instance(workspace, "workspace", SCvxWorkspace)
    if practical_stop is not None:
        validation.instance(practical_stop, "practical_stop", PracticalStop)
    if not isinstance(solver, str) or solver.upper() not in cp.installed_solvers():
        raise ValueError(f"solver must be the name of an installed cvxpy solver {cp.installed_solvers()}; got "
                         f"{solver!r}")
    norms = np.linalg.norm(u_ref, axis=1)
    over = norms > umax
    u_ref[over] *= (umax[over] / norms[over])[:, None]
    x_tc = None if x_final is None else validation.as_state(x_final, "x_final", batch=False)
    if x_tc is not None:
        x_ref[-1] = x_tc
    dt = np.diff(t)
    w_u = np.zeros(n)
    w_u[:-1] += dt / 2.0
    w_u[1:] += dt / 2.0
    use_info = info is not None and alpha > 0
    al = st.method == "augmented_lagrangian"

    structure = (n, x_tc is not None, info_node if use_info else None, con_specs, umax == 0)
    sub = _Subproblem(*structure[:4], coast=structure[4]) if workspace is None else workspace._subproblem(*structure)
    sub.x_ic.value = x_ref[0]
    sub.x_tc.value = x_ref[-1] if x_tc is None else x_tc
    sub.umax.value = umax
    sub.w_u.value = (1.0 - alpha) * w_u
    sub.gamma_dt.value = np.zeros(n - 1) if al else st.defect_weight * dt
    for c in sub.con:
        c["gamma"].value = 0.0 if al else st.defect_weight
    lam = np.zeros((n - 1, 6))
    mus = [np.zeros(m) for _, m in con_specs]
    w = st.penalty_weight0 if al else 0.0
    solve_opts = {}
    if solver.upper() == "CLARABEL":
        solve_opts = dict(tol_gap_abs=st.solver_tol, tol_gap_rel=st.solver_tol, tol_feas=st.solver_tol,
                          tol_ktratio=1e-8, max_iter=500)

    def penalty(defects, viol):
        """Nonlinear penalty of defects (N-1, 6) and constraint violations (list of (m,) arrays, >= 0)."""
        if al:
            p = float(np.sum(lam * defects) + 0.5 * w * np.sum(defects**2))
            for mu, v in zip(mus, viol):
                p += float(mu @ v + 0.5 * w * v @ v)
            return p
        return float(st.defect_weight * (np.sum(dt * np.abs(defects).sum(axis=1)) + sum(v.sum() for v in viol)))

    def evaluate(x, u, order):
        """Nonlinear pieces at (x, u): FOH model, information value (and gradient), constraint values."""
        t0 = time.perf_counter()
        model = _foh_discretize(system, t, x, u, DEFAULT_TOL)
        t1 = time.perf_counter()
        ival, grad = 0.0, np.zeros(6)
        if info is not None:
            ival = validation.real(info(x[info_node], 0), "info(x, 0)")
            if use_info and order >= 1:
                grad = validation.as_array(info(x[info_node], 1)[1], "info(x, 1) gradient", shape=(6,))
        t2 = time.perf_counter()
        cvals = []
        for i, (obj, (node, m)) in enumerate(zip(constraints, con_specs)):
            c, C = obj(x[node])
            cvals.append((validation.as_array(c, f"constraints[{i}] value", shape=(m,)),
                          validation.as_array(C, f"constraints[{i}] Jacobian", shape=(m, 6))))
        return dict(model=model, info=ival, grad=grad, cons=cvals, t_discretize=t1 - t0, t_info=t2 - t1)

    def cost_of(x, u, ev):
        viol = [np.maximum(c, 0.0) for c, _ in ev["cons"]]
        obj = (1.0 - alpha) * _impulse(dt, u) - (alpha * ev["info"] if use_info else 0.0)
        return obj + penalty(ev["model"].defects, viol), obj

    def feasibility(ev):
        d = float(np.max(np.linalg.norm(ev["model"].defects, axis=1)))
        v = max([float(np.max(c)) for c, _ in ev["cons"]] + [0.0])
        return d, v

    def hessian_factor(x, g0):
        if st.information_model == "linear":
            return np.zeros((6, 6)), 0.0
        t0 = time.perf_counter()
        if hasattr(info, "hessian"):
            H = validation.as_array(info.hessian(x), "info.hessian(x)", shape=(6, 6))
        else:  # forward differences of the gradient from the one just computed
            H = finite_difference_hessian(lambda z: info(z, 1)[1], x, st.hessian_step, g0=g0)
        return _concave_part(H, st.curvature_floor), time.perf_counter() - t0

    ev = evaluate(x_ref, u_ref, 1)
    J_ref, obj_ref = cost_of(x_ref, u_ref, ev)
    Lfac, t_hess = hessian_factor(x_ref[info_node], ev["grad"]) if use_info else (None, 0.0)
    x_hess = x_ref[info_node].copy() if info_node is not None else None
    eta = st.eta0
    threshold = st.multiplier_threshold0
    last_progress, best_defect = 0, feasibility(ev)[0]
    quiet = 0  # consecutive accepted steps meeting the practical stopping rule (practical_stop)
    history: list = []
    bar = _progress(range(st.max_iter), desc=f"SCvx alpha={alpha:g}", enabled=progress)
    try:
        for it in bar:
            sub.set_model(ev["model"])
            sub.xbar.value = x_ref
            sub.ubar.value = u_ref
            sub.eta.value = eta
            sub.lam.value = lam
            sub.half_w.value = 0.5 * w
            if use_info:
                sub.g.value = alpha * ev["grad"]
                sub.L.value = np.sqrt(alpha) * Lfac
            for c, (cv, CJ), mu in zip(sub.con, ev["cons"], mus):
                c["c"].value, c["C"].value, c["mu"].value = cv, CJ, mu
            t0 = time.perf_counter()
            try:
                with warnings.catch_warnings():  # "inaccurate" is recorded in the history and judged by rho
                    warnings.simplefilter("ignore", UserWarning)
                    # Clarabel reuses its solver object (data update) from the second solve of a run on; the first
                    # solve of every run starts a new one, so a reused (workspace) problem solves as a fresh one
                    status = sub.solve(solver, it == 0, solve_opts)
            except cp.error.SolverError as exc:
                raise SCvxError(f"convex subproblem failed at iteration {it}: {exc}", history) from exc
            t_solve = time.perf_counter() - t0
            if status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
                raise SCvxError(f"convex subproblem {status} at iteration {it} (eta = {eta:g})", history)
            x_new, u_new, nu = sub.x.value.copy(), sub.u.value.copy(), sub.nu.value
            unew = np.linalg.norm(u_new, axis=1)  # onto the bounds (solver round-off only)
            over = unew > umax
            u_new[over] *= (umax[over] / unew[over])[:, None]
            step = float(np.max(sub.step.value))
            tr_active = step >= (1.0 - st.active_tol) * eta
            # model cost L at the new point (the same pieces as J, each replaced by its convex model)
            dxs = x_new[info_node] - x_ref[info_node] if use_info else np.zeros(6)
            info_model = (ev["info"] + ev["grad"] @ dxs - 0.5 * float(np.sum((Lfac.T @ dxs) ** 2))) if use_info else 0.0
            slack = [np.maximum(c["s"].value, 0.0) for c in sub.con]
            pen_model = penalty(nu, slack)
            L_new = (1.0 - alpha) * _impulse(dt, u_new) - alpha * info_model + pen_model
            try:
                if _inside_primaries(system, x_new[:, :3]):
                    raise ImpactError("a primary", float(t[0]), started_inside=True,
                                      detail="a node of the trial step lies inside it")
                ev_new = evaluate(x_new, u_new, 0)
            except ImpactError as exc:
                # A trial step through a primary has no nonlinear cost to compare: rejected like a step that raises
                # the cost (rho = -inf), the trust region shrinks, and the reference is kept.
                history.append(dict(iteration=it, cost=J_ref, new_cost=np.inf, predicted=J_ref - L_new,
                                    actual=-np.inf, rho=-np.inf, eta=eta, accepted=False, tr_active=bool(tr_active),
                                    step=step, max_defect=np.nan, max_violation=np.nan, model_error_defect=np.nan,
                                    model_error_info=np.nan, penalty_weight=w, multiplier_update=False,
                                    information=np.nan, impulse=_impulse(dt, u_new), t_discretize=0.0, t_info=0.0,
                                    t_solve=t_solve, t_hessian=0.0, status=f"impact: {exc}"))
                eta = eta / st.beta_shrink
                if st.stall_iter and it - last_progress >= st.stall_iter:
                    raise SCvxError(f"stalled: no progress in {st.stall_iter} iterations (eta = {eta:.1e}, largest "
                                    f"defect {feasibility(ev)[0]:.2e})", history) from exc
                if eta < st.eta_min:
                    raise SCvxError(f"trust region collapsed (eta < {st.eta_min:g}) at iteration {it}: every trial "
                                    f"step passes through a primary ({exc})", history) from exc
                continue
            J_new, obj_new = cost_of(x_new, u_new, ev_new)
            pen_new = J_new - obj_new
            predicted = J_ref - L_new
            actual = J_ref - J_new
            scale = 1.0 + abs(J_ref)
            if abs(predicted) <= st.noise_tol * scale:
                rho = 1.0
            elif predicted > 0:
                rho = actual / predicted
            else:
                rho = -np.inf
            accepted = rho >= st.rho0
            max_def_new, viol_new = feasibility(ev_new)
            rec = dict(iteration=it, cost=J_ref, new_cost=J_new, predicted=predicted, actual=actual, rho=rho,
                       eta=eta, accepted=bool(accepted), tr_active=bool(tr_active), step=step,
                       max_defect=max_def_new, max_violation=viol_new,
                       model_error_defect=pen_new - pen_model,
                       model_error_info=(-alpha * (ev_new["info"] - info_model)) if use_info else 0.0,
                       penalty_weight=w, multiplier_update=False, information=ev_new["info"],
                       impulse=_impulse(dt, u_new), t_discretize=ev_new["t_discretize"], t_info=ev_new["t_info"],
                       t_solve=t_solve, t_hessian=0.0, status=str(status))
            history.append(rec)
            if rho < st.rho1:
                eta = eta / st.beta_shrink
            elif rho >= st.rho2:
                eta = min(eta * st.beta_grow, st.eta_max)
            # the curvature model is refreshed when the window-start state moved, or when the information part
            # of the model error was a sizeable share of the predicted decrease (the curvature has changed)
            poor_model = use_info and abs(rec["model_error_info"]) > st.hessian_error_ratio * abs(predicted)
            if use_info and not accepted and poor_model and np.any(x_hess != x_ref[info_node]):
                Lfac, t_hess = hessian_factor(x_ref[info_node], ev["grad"])
                x_hess = x_ref[info_node].copy()
                rec["t_hessian"] = t_hess
            if accepted:
                x_ref, u_ref, ev = x_new, u_new, ev_new
                obj_change = abs(obj_new - obj_ref)
                obj_ref = obj_new
                small = obj_change <= st.tol * scale
                feasible = max_def_new <= st.defect_tol and viol_new <= st.defect_tol
                if small and feasible and not tr_active:
                    return SCvxResult(t, x_ref, u_ref, alpha, obj_ref, _impulse(dt, u_ref),
                                      ev["info"] if info is not None else float("nan"), max_def_new, history)
                if practical_stop is not None:
                    ps = practical_stop
                    calm = max(abs(actual), obj_change) <= ps.cost_tol * scale
                    closed = max_def_new <= ps.defect_tol and viol_new <= ps.defect_tol
                    quiet = quiet + 1 if calm and closed else 0
                    if quiet >= ps.window:
                        return SCvxResult(t, x_ref, u_ref, alpha, obj_ref, _impulse(dt, u_ref),
                                          ev["info"] if info is not None else float("nan"), max_def_new, history,
                                          stopped_by="practical")
                # the iteration goes on: gradient (and Hessian) at the new reference (not computed on the converged
                # step, where nothing would use them); the value is info(x, 0)'s
                t0 = time.perf_counter()
                t_hess = 0.0
                if use_info:
                    ev["grad"] = validation.as_array(info(x_ref[info_node], 1)[1], "info(x, 1) gradient", shape=(6,))
                    if poor_model or np.linalg.norm(x_ref[info_node] - x_hess) > st.hessian_refresh:
                        Lfac, t_hess = hessian_factor(x_ref[info_node], ev["grad"])
                        x_hess = x_ref[info_node].copy()
                    rec["t_hessian"] = t_hess
                rec["t_info"] += time.perf_counter() - t0 - t_hess
                if al and (abs(actual) <= threshold * scale or (not tr_active and abs(actual) <= 1e2 * st.tol * scale)):
                    lam = lam + w * ev["model"].defects
                    mus = [np.maximum(mu + w * c, 0.0) for mu, (c, _) in zip(mus, ev["cons"])]
                    w = min(w * st.penalty_growth, st.penalty_weight_max)
                    threshold *= st.multiplier_threshold_decay
                    rec["multiplier_update"] = True
                if actual > 10.0 * st.noise_tol * scale or rec["multiplier_update"] or max_def_new < 0.5 * best_defect:
                    last_progress = it
                best_defect = min(best_defect, max_def_new)
                J_ref, obj_ref = cost_of(x_ref, u_ref, ev)
            if st.stall_iter and it - last_progress >= st.stall_iter:
                raise SCvxError(f"stalled: no progress in {st.stall_iter} iterations (eta = {eta:.1e}, largest defect "
                                f"{feasibility(ev)[0]:.2e})", history)
            if eta < st.eta_min:
                raise SCvxError(f"trust region collapsed (eta < {st.eta_min:g}) at iteration {it} with largest "
                                f"defect {feasibility(ev)[0]:.2e}", history)
    finally:
        if hasattr(bar, "close"):
            bar.close()
    raise SCvxError(f"no convergence in {st.max_iter} iterations (largest defect {feasibility(ev)[0]:.2e})", history)


@dataclass
class SweepResult:
    """Best solution per homotopy weight over an upward and a downward sweep.

    Attributes
    ----------
    alphas : ndarray (K,)
    best : list of SCvxResult or None
        Lowest-cost converged solution per alpha (None if every attempt failed).
    source : list of str
        Which sweep gave the best (``"up"`` or ``"down"``).
    attempts : list of dict
        Every run: ``alpha, direction, converged, cost, iterations, error``.
    """

    alphas: np.ndarray
    best: list
    source: list
    attempts: list

    def column(self, name: str) -> np.ndarray:
        """``impulse``, ``information``, ``cost``, ``iterations`` or ``max_defect`` of the best per alpha (NaN if none)."""
        validation.choice(name, "name", ("impulse", "information", "cost", "iterations", "max_defect", "alpha"))
        return np.array([np.nan if b is None else float(getattr(b, name)) for b in self.best])


def homotopy_sweep(solve, alphas, x_guess, u_guess, *, directions=("up", "down"), progress: bool = False
                   ) -> SweepResult:
    """Sweep the homotopy weight upward (warm starts from the previous alpha) and downward, keep the best cost.

    Parameters
    ----------
    solve : callable
        ``solve(alpha, x_guess, u_guess) -> SCvxResult`` (e.g. a ``functools.partial`` of :func:`solve_scvx`).
    alphas : array_like (K,)
        Increasing homotopy weights in [0, 1].
    x_guess, u_guess : array_like
        Guess of the first run of the upward sweep (e.g. the ballistic trajectory).  The downward sweep starts
        from the upward sweep's solution at the largest alpha.
    directions : tuple of {"up", "down"}
    progress : bool

    Returns
    -------
    SweepResult
        The problem has several local optima; sweeping both ways and keeping the lower cost per alpha gives
        a front that is monotone in alpha (impulse and information non-decreasing) where one sweep alone may not.
    """
    validation.callable_(solve, "solve")
    a = validation.as_array(alphas, "alphas", ndim=(1,), min_size=1)
    if np.any(np.diff(a) <= 0) or a[0] < 0 or a[-1] > 1:
        raise ValueError("alphas must be strictly increasing within [0, 1]")
    xg = validation.as_array(x_guess, "x_guess", ndim=(2,), last=6, min_size=1)
    validation.as_array(u_guess, "u_guess", shape=(xg.shape[0], 3))
    directions = validation.one_or_many(directions, "directions", str, "str")
    for d in directions:
        validation.choice(d, "directions", ("up", "down"))
    progress = validation.boolean(progress, "progress")
    best, source, attempts = [None] * a.size, [""] * a.size, []
    runs = []
    if "up" in directions:
        runs += [("up", i) for i in range(a.size)]
    if "down" in directions:
        runs += [("down", i) for i in range(a.size - 1, -1, -1)]
    guess = {"up": (x_guess, u_guess), "down": None}
    for direction, i in _progress(runs, desc="alpha sweep", enabled=progress):
        g = guess[direction]
        if g is None:  # the downward sweep starts from the upward sweep's solution at the top, if any
            if best[-1] is not None:
                guess["down"] = (best[-1].x, best[-1].u)
                continue  # re-solving the top from its own solution would only repeat it
            g = (x_guess, u_guess)
        try:
            res = validation.instance(solve(float(a[i]), g[0], g[1]), "solve(alpha, x_guess, u_guess) result",
                                   SCvxResult)
        except SCvxError as exc:
            attempts.append(dict(alpha=float(a[i]), direction=direction, converged=False, cost=np.nan,
                                 iterations=len(exc.history), error=exc.reason))
            continue
        attempts.append(dict(alpha=float(a[i]), direction=direction, converged=True, cost=res.cost,
                             iterations=res.iterations, error=""))
        guess[direction] = (res.x, res.u)
        if best[i] is None or res.cost < best[i].cost - 1e-12 * (1 + abs(res.cost)):
            best[i], source[i] = res, direction
    return SweepResult(a, best, source, attempts)

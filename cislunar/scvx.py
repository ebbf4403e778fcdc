r"""Successive convexification (SCvx) with first-order hold for a low-thrust observer (Wolf & Jones, §SCvx).

Each iteration linearises the controlled CR3BP about the reference nodes (:mod:`cislunar.discretization`,
Eqs. 28-31), solves the convex subproblem (Eq. 30)

.. math::

    \min\ -\alpha_h\,g^\top x_{k^*} + (1-\alpha_h)\sum_k\tfrac{\Delta t_k}{2}(\|u_k\|_2+\|u_{k+1}\|_2)
          + \gamma\sum_k\Delta t_k\|E_k\epsilon_k\|_1

    \text{s.t.}\ x_{k+1} = A_kx_k + B_k^-u_k + B_k^+u_{k+1} + r_k + E_k\epsilon_k,\quad x_0 = x_{ic},\ x_{N-1} = x_{tc},
    \ \|u_k\|_2\le u_{max,k},\ \|x_k-\bar x_k\|_2 + \|u_k-\bar u_k\|_2\le\eta,

and accepts or rejects the step with the ratio of actual to predicted cost decrease (Eq. 36) and the trust-region
rules of Table 1.  The linear term :math:`g^\top x_{k^*}` is the first-order mutual-information approximation of
Eq. 44 (gradient of the information with respect to the observer state at the window start node :math:`k^*`,
:func:`cislunar.information.mutual_information_gradient`); with :math:`\alpha_h = 0` the problem is minimum
impulse.

Differences from the printed formulation, all documented choices: the defect penalty uses one weight
:math:`\Delta t_k` per interval instead of the trapezoid of Eq. 42-43 (which would need a defect at the last node,
where there is none); the nonlinear cost (Eq. 42) uses the multiple-shooting defects of Eq. 34 and the caller's
information function.  The subproblem is built once with ``cvxpy.Parameter`` objects and re-solved with Clarabel.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import _checks
from .discretization import foh_discretize
from .dynamics import CR3BP

__all__ = ["SCvxSettings", "SCvxResult", "SCvxError", "solve_scvx"]


class SCvxError(RuntimeError):
    """SCvx failed (subproblem infeasible or no convergence); carries the iteration history."""

    def __init__(self, message: str, history):
        super().__init__(f"{message}; last iterations: {history[-3:] if history else []}")
        self.history = history


@dataclass(frozen=True)
class SCvxSettings:
    """Trust-region and penalty settings (Malyuta et al. 2022; Mao et al. 2018; values recorded in the notebooks).

    Attributes
    ----------
    rho0, rho1, rho2 : float
        Acceptance thresholds of Table 1 (0 <= rho0 < rho1 < rho2 <= 1).
    beta_shrink, beta_grow : float
        Trust-region shrink and growth factors (> 1).
    eta0, eta_min, eta_max : float
        Initial, smallest and largest trust-region radius (non-dimensional).
    defect_weight : float
        :math:`\\gamma` of Eqs. 42-43, large enough to drive the virtual control to zero.
    max_iter : int
    tol : float
        Convergence when the predicted cost decrease falls below ``tol`` (relative to 1 + |J|) on an accepted step
        and the largest defect is below ``defect_tol``.
    defect_tol : float
        Largest acceptable multiple-shooting defect norm (LU, LU/TU).
    """

    rho0: float = 0.0
    rho1: float = 0.1
    rho2: float = 0.7
    beta_shrink: float = 2.0
    beta_grow: float = 2.0
    eta0: float = 0.05
    eta_min: float = 1e-8
    eta_max: float = 1.0
    defect_weight: float = 1e3
    max_iter: int = 60
    tol: float = 1e-7
    defect_tol: float = 1e-8

    def __post_init__(self):
        if not 0.0 <= self.rho0 < self.rho1 < self.rho2 <= 1.0:
            raise ValueError(f"need 0 <= rho0 < rho1 < rho2 <= 1; got {self.rho0}, {self.rho1}, {self.rho2}")
        for name in ("beta_shrink", "beta_grow"):
            if not getattr(self, name) > 1.0:
                raise ValueError(f"{name} must be > 1; got {getattr(self, name)}")
        if not 0 < self.eta_min <= self.eta0 <= self.eta_max:
            raise ValueError("need 0 < eta_min <= eta0 <= eta_max")
        _checks.positive(self.defect_weight, "defect_weight")


@dataclass
class SCvxResult:
    """Converged SCvx solution.

    Attributes
    ----------
    t : ndarray (N,)
    x : ndarray (N, 6)
        Node states (LU, LU/TU).
    u : ndarray (N, 3)
        Node accelerations (LU/TU^2), first-order hold in between.
    cost : float
        Nonlinear cost (Eq. 42).
    impulse : float
        Trapezoid total impulse :math:`\\sum\\Delta t_k(\\|u_k\\|+\\|u_{k+1}\\|)/2`, LU/TU.
    max_defect : float
        Largest multiple-shooting defect norm.
    history : list of dict
        Per iteration: cost, predicted and actual decrease, rho, eta, accepted, max defect.
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    cost: float
    impulse: float
    max_defect: float
    history: list = field(default_factory=list)


def _impulse(t, u):
    nrm = np.linalg.norm(u, axis=1)
    return float(np.sum(np.diff(t) * (nrm[:-1] + nrm[1:]) / 2.0))


class _Subproblem:
    """The convex subproblem of Eq. 30, built once with parameters."""

    def __init__(self, n: int, has_terminal: bool, k_star: int | None):
        import cvxpy as cp

        self.n = n
        self.x = cp.Variable((n, 6))
        self.u = cp.Variable((n, 3))
        self.eps = cp.Variable((n - 1, 6))
        self.A = [cp.Parameter((6, 6)) for _ in range(n - 1)]
        self.Bm = [cp.Parameter((6, 3)) for _ in range(n - 1)]
        self.Bp = [cp.Parameter((6, 3)) for _ in range(n - 1)]
        self.E = [cp.Parameter((6, 6)) for _ in range(n - 1)]
        self.r = cp.Parameter((n - 1, 6))
        self.xbar = cp.Parameter((n, 6))
        self.ubar = cp.Parameter((n, 3))
        self.eta = cp.Parameter(nonneg=True)
        self.umax = cp.Parameter(n, nonneg=True)
        self.x_ic = cp.Parameter(6)
        self.x_tc = cp.Parameter(6)
        self.w_u = cp.Parameter(n, nonneg=True)  # (1 - alpha) * trapezoid weights of the node control norms
        self.WE = [cp.Parameter((6, 6)) for _ in range(n - 1)]  # gamma * dt_k * E_k (keeps the problem DPP)
        self.g = cp.Parameter(6)  # alpha * information gradient at node k_star
        cons = [self.x[0] == self.x_ic]
        if has_terminal:
            cons.append(self.x[n - 1] == self.x_tc)
        for k in range(n - 1):
            cons.append(self.x[k + 1] == self.A[k] @ self.x[k] + self.Bm[k] @ self.u[k] + self.Bp[k] @ self.u[k + 1]
                        + self.r[k] + self.E[k] @ self.eps[k])
        unorm = cp.norm(self.u, 2, axis=1)
        cons.append(unorm <= self.umax)
        cons.append(cp.norm(self.x - self.xbar, 2, axis=1) + cp.norm(self.u - self.ubar, 2, axis=1) <= self.eta)
        defect_terms = [cp.norm1(self.WE[k] @ self.eps[k]) for k in range(n - 1)]
        objective = self.w_u @ unorm + cp.sum(defect_terms)
        if k_star is not None:
            objective = objective - self.g @ self.x[k_star]
        self.k_star = k_star
        self.problem = cp.Problem(cp.Minimize(objective), cons)


def solve_scvx(system: CR3BP, t_nodes, x_guess, u_guess, u_max, *, x_final=None, info=None, alpha: float = 0.0,
               settings: SCvxSettings | None = None, solver: str = "CLARABEL", progress: bool = False) -> SCvxResult:
    """Solve the observer trajectory problem by SCvx.

    Parameters
    ----------
    system : CR3BP
    t_nodes : array_like, shape (N,)
        Node times (e.g. Sundman-spaced), TU.
    x_guess, u_guess : array_like, shapes (N, 6), (N, 3)
        Initial reference (guess controls above ``u_max`` are scaled down onto the bound); ``x_guess[0]`` is the
        fixed initial state and the last node is replaced by
        ``x_final`` when given (the reference must satisfy the boundary conditions; the mismatch shows up as
        defects, which the virtual control and the penalty then remove).
    u_max : array_like, shape (N,)
        Bound on each node's acceleration norm, LU/TU^2 (zero inside observation windows).
    x_final : array_like, shape (6,), optional
        Terminal state constraint (Eq. 30d).
    info : callable, optional
        ``info(x_nodes) -> (value, gradient, k_star)``: the mutual information of the observation window (nats),
        its gradient (6,) with respect to the observer state at node ``k_star``.  ``k_star`` must not change
        between calls.
    alpha : float
        Homotopy weight :math:`\\alpha_h` in [0, 1].
    settings : SCvxSettings
    solver : str
        cvxpy solver name.
    progress : bool
        tqdm progress bar over iterations.

    Returns
    -------
    SCvxResult

    Raises
    ------
    SCvxError
        Subproblem infeasible, trust region collapsed, or no convergence within ``max_iter`` (with history).
    """
    import cvxpy as cp

    st = settings or SCvxSettings()
    t = _checks.time_grid(t_nodes, "t_nodes", increasing=True)
    n = t.size
    x_ref = _checks.as_array(x_guess, "x_guess", shape=(n, 6)).copy()
    u_ref = _checks.as_array(u_guess, "u_guess", shape=(n, 3)).copy()
    umax = _checks.as_array(u_max, "u_max", shape=(n,))
    if np.any(umax < 0):
        raise ValueError("u_max must be non-negative")
    alpha = _checks.in_range(alpha, "alpha", 0.0, 1.0)
    # project the guess controls onto the bounds so that the first trust region can contain a feasible point
    norms = np.linalg.norm(u_ref, axis=1)
    over = norms > umax
    u_ref[over] *= (umax[over] / norms[over])[:, None]
    x_tc = None if x_final is None else _checks.as_state(x_final, "x_final", batch=False)
    if x_tc is not None:
        x_ref[-1] = x_tc  # the reference must meet the boundary conditions; its defects carry the mismatch
    dt = np.diff(t)
    w_u = np.zeros(n)
    w_u[:-1] += dt / 2.0
    w_u[1:] += dt / 2.0

    info_val, grad, k_star = (0.0, np.zeros(6), None) if info is None else info(x_ref)
    sub = _Subproblem(n, x_tc is not None, k_star if info is not None and alpha > 0 else None)
    sub.x_ic.value = x_ref[0]
    sub.x_tc.value = x_ref[-1] if x_tc is None else x_tc
    sub.umax.value = umax
    sub.w_u.value = (1.0 - alpha) * w_u

    def nonlinear_cost(x, u):
        model = foh_discretize(system, t, x, u)
        defects = np.linalg.norm(model.defects, ord=1, axis=1)
        val = 0.0 if info is None else info(x)[0]
        J = -alpha * val + (1.0 - alpha) * _impulse(t, u) + st.defect_weight * float(np.sum(dt * defects))
        return J, model, float(np.max(np.linalg.norm(model.defects, axis=1))), val

    J_ref, model, max_def, info_val = nonlinear_cost(x_ref, u_ref)
    eta = st.eta0
    history = []
    iterator = range(st.max_iter)
    if progress:
        from tqdm.auto import tqdm

        iterator = tqdm(iterator, desc=f"SCvx alpha={alpha:g}")
    for it in iterator:
        for k in range(n - 1):
            sub.A[k].value, sub.Bm[k].value, sub.Bp[k].value, sub.E[k].value = (
                model.A[k], model.Bm[k], model.Bp[k], model.E[k])
            sub.WE[k].value = st.defect_weight * dt[k] * model.E[k]
        sub.r.value = model.r
        sub.xbar.value = x_ref
        sub.ubar.value = u_ref
        sub.eta.value = eta
        if sub.k_star is not None:
            _, grad, _ = info(x_ref)
            sub.g.value = alpha * grad
        else:
            sub.g.value = np.zeros(6)
        try:
            sub.problem.solve(solver=solver)
        except cp.error.SolverError as exc:
            raise SCvxError(f"convex subproblem failed at iteration {it}: {exc}", history) from exc
        if sub.problem.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
            raise SCvxError(f"convex subproblem {sub.problem.status} at iteration {it} (eta = {eta:g})", history)
        x_new, u_new = sub.x.value.copy(), sub.u.value.copy()
        # linearised cost at the new point (Eq. 43): the information enters through its first-order model
        lin_info = 0.0 if info is None else info_val + (grad @ (x_new[k_star] - x_ref[k_star]) if k_star is not None
                                                         else 0.0)
        eps_cost = float(np.sum(dt * np.linalg.norm(np.einsum("kij,kj->ki", model.E, sub.eps.value), ord=1, axis=1)))
        L_new = -alpha * lin_info + (1.0 - alpha) * _impulse(t, u_new) + st.defect_weight * eps_cost
        J_new, model_new, max_def_new, info_new = nonlinear_cost(x_new, u_new)
        predicted = J_ref - L_new
        actual = J_ref - J_new
        rho = actual / predicted if predicted > 0 else (1.0 if abs(actual) <= 1e-14 else -np.inf)
        accepted = rho >= st.rho0
        history.append(dict(iteration=it, cost=J_ref, new_cost=J_new, predicted=predicted, actual=actual, rho=rho,
                            eta=eta, accepted=bool(accepted), max_defect=max_def_new))
        if accepted:
            x_ref, u_ref, J_ref, model, max_def, info_val = x_new, u_new, J_new, model_new, max_def_new, info_new
        if rho < st.rho1:
            eta = eta / st.beta_shrink
        elif rho >= st.rho2:
            eta = min(eta * st.beta_grow, st.eta_max)
        if accepted and abs(predicted) <= st.tol * (1.0 + abs(J_ref)) and max_def <= st.defect_tol:
            return SCvxResult(t, x_ref, u_ref, J_ref, _impulse(t, u_ref), max_def, history)
        if eta < st.eta_min:
            if max_def <= st.defect_tol:
                return SCvxResult(t, x_ref, u_ref, J_ref, _impulse(t, u_ref), max_def, history)
            raise SCvxError(f"trust region collapsed (eta < {st.eta_min:g}) with defects {max_def:.2e}", history)
    raise SCvxError(f"no convergence in {st.max_iter} iterations (max defect {max_def:.2e})", history)

"""Malformed-argument specs (issue 11) for covariance, information, discretization, scvx, reference, lpv, observers.

Loaded by ``tests/test_reliability.py`` (plugin protocol: ``MODULES``, ``EXEMPT``, ``specs(Spec, lazy)``).  Every
public function, every constructor that takes user input and every public method with arguments gets one cheap
valid call (a few nodes, short spans, two LMI vertices) and the kind of each argument; the sweep then feeds each
argument the malformed values of its kind.  Expensive valid objects are built once (``functools.lru_cache``).
"""

from __future__ import annotations

import functools

import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import lpv, observers
from cislunar.guidance import discretization, scvx
from cislunar.papers.nychka_bhattacharya import scenarios as nb_scenarios
from cislunar.papers.nychka_bhattacharya import sensing_precision as nb_sensing
from cislunar.papers.wolf_jones import reference
from cislunar.sensing import covariance, information
from cislunar.sensing.measurements import AZIMUTH_ELEVATION

MODULES = [covariance, information, discretization, scvx, reference, lpv, observers]
# Output containers (CovarianceHistory, AugmentedLinearization, ObjectArcs, FOHModel, SCvxResult, SCvxError,
# SweepResult, TimingResult, RowCheck, ObserverDesign, Verification, ResonantOrbit, Scenario, SensitivityStudy,
# ObserverRun, InfeasibleLMIError) are built by the package and are not input boundaries; their public methods that
# take arguments are swept below.  Every module-level public function has a spec.  Arguments that accept any
# square matrix (symmetrize, concave_part) or any planar state/position stack (CR3BPLPV.rho, angles, measure) are
# swept with "arr_finite" (their shape refusals are tested in tests/test_validation_estimation.py).
# The constructors of InformationKernel, WindowAssembler and SCvxWorkspace are swept, WindowAssembler's call and
# InformationKernel.value / value_gradient (their fast path converts F, H, dF, dH with one np.asarray each and
# re-raises numpy's conversion errors naming the argument; a dF/dH pair whose last axes differ names both).
EXEMPT: dict = {}

X_DRO = np.array([0.8, 0.0, 0.0, 0.0, 0.52, 0.0])
SPD3 = np.diag([1.0, 2.0, 3.0])
SPD6 = np.eye(6) * 1e-6
T3 = np.array([0.0, 0.05, 0.1])


# ------------------------------------------------------------------------------------------ a small linear system
def _linear_system():
    """N = 3 measurement times, n = 2 states, M = 2 measurements, p = 2 parameters (all tiny and well posed)."""
    P0 = np.array([[2.0, 0.3], [0.3, 1.0]])
    F = np.array([[[1.0, 0.1], [0.0, 1.0]]] * 2)
    Q = np.eye(2) * 1e-2
    H = np.array([[[1.0, 0.0], [0.0, 1.0]], [[1.0, 0.5], [0.0, 1.0]], [[0.3, 1.0], [1.0, 0.0]]])
    R = np.diag([0.5, 0.4])
    dF = np.zeros((2, 2, 2, 2))
    dF[:, 0, 1, 0] = 1.0
    dH = np.zeros((3, 2, 2, 2))
    dH[:, 0, 0, 1] = 1.0
    return dict(P0=P0, F=F, Q=Q, H=H, R=R), dict(dF=dF, dH=dH)


LIN_KINDS = dict(P0="spd", F="arr", Q="psd", H="arr", R="spd")
DER_KINDS = dict(dF="arr", dH="arr")


# ----------------------------------------------------------------------------------------- cached valid objects
@functools.lru_cache(maxsize=None)
def _arcs():
    return (covariance.propagate_arcs(em, X_DRO, T3, q=1e-10),
            covariance.propagate_arcs(em, np.array([1.1, 0.0, 0.0, 0.0, -0.2, 0.0]), T3, q=1e-10))


@functools.lru_cache(maxsize=None)
def _lin():
    return covariance.linearize_augmented(em, X_DRO, np.array([[1.1, 0.0, 0.0, 0.0, -0.2, 0.0]]), T3,
                                          AZIMUTH_ELEVATION, np.eye(2) * 1e-8, np.eye(12) * 1e-6, q=1e-10,
                                          derivatives=True)


@functools.lru_cache(maxsize=None)
def _assembler():
    return covariance.WindowAssembler(AZIMUTH_ELEVATION, np.eye(2) * 1e-8, np.eye(12) * 1e-6, _arcs()[1],
                                      Q=np.eye(12) * 1e-12)


@functools.lru_cache(maxsize=None)
def _x_ballistic():
    from cislunar.cr3bp.propagation import propagate

    return propagate(em, X_DRO, T3).x


@functools.lru_cache(maxsize=None)
def _foh_model():
    return discretization.foh_discretize(em, T3, _x_ballistic(), np.zeros((3, 3)))


def _fake_solve(alpha, x, u):
    x, u = np.asarray(x, dtype=float), np.asarray(u, dtype=float)
    return scvx.SCvxResult(T3, x, u, alpha, 0.0, 0.0, float("nan"), 0.0, [])


@functools.lru_cache(maxsize=None)
def _sweep():
    return scvx.homotopy_sweep(_fake_solve, [0.0, 0.5], _x_ballistic(), np.zeros((3, 3)), directions=("up",))


@functools.lru_cache(maxsize=None)
def _table_row():
    return reference.load_wolf_jones_table()[0]


def _row_check():
    return reference.verify_table_row(em, reference.load_wolf_jones_table()[1])


MODEL = lpv.CR3BPLPV()
S_PLANAR = np.array([[-0.3, 0.05, 0.0, -1.5], [-0.25, 0.1, 0.2, -1.6]])
RHO2 = MODEL.rho(S_PLANAR)


@functools.lru_cache(maxsize=None)
def _lmi():
    return lpv.PrecisionLMI.for_cr3bp(MODEL, RHO2, "h2", sensors=[0, 1])


@functools.lru_cache(maxsize=None)
def _design():
    return _lmi().solve(0.0013)


def _box():
    hi = RHO2[0].copy()
    hi[0] = RHO2[1, 0] if RHO2[1, 0] > RHO2[0, 0] else RHO2[0, 0] * 1.01
    return lpv.ParameterBox(RHO2[0], hi)  # one free parameter: two vertices


@functools.lru_cache(maxsize=None)
def _resonant():
    return lpv.resonant_orbit(em, 3, 1, 0.2)


def _study():
    one = np.ones((1, 1, 1))
    st = np.full((1, 1, 1), "optimal")
    return nb_sensing.SensitivityStudy(orbits=((2, 1, 0.3),), r13_max=np.ones(1), period=np.ones(1),
                                structures=("acceleration",), levels=np.array([1e-3]), gamma=0.0013,
                                pole_radius=1000.0, h2_kappa=one * 500.0, hinf_kappa=one * 600.0, h2_status=st,
                                hinf_status=st, h2_gain=one, hinf_gain=one, seconds=0.0)


T_OBS = np.array([0.0, 0.01, 0.02, 0.03])


def _truth():
    # a slow drift far from the Earth-Moon line (no singular triangulation), planar states on T_OBS
    x = np.array([-0.3, 0.1, 0.0, -1.5])
    return np.array([x + np.array([0.0, -1.5 * t, 0.0, 0.0]) for t in T_OBS])


@functools.lru_cache(maxsize=None)
def _meas():
    return observers.make_measurements(MODEL, T_OBS, _truth(), 0.01, np.random.default_rng(0))


def specs(Spec, lazy):
    S = Spec
    s = []
    rng = lazy(lambda: np.random.default_rng(0))
    lin, der = _linear_system()

    # ------------------------------------------------------------------------------------------- covariance
    C = covariance
    s.append(S("symmetrize", C.symmetrize, dict(P=SPD3, name="P"), dict(P="arr_finite", name="instance_str")))
    for name in ("check_spd", "cholesky_spd"):
        s.append(S(name, getattr(C, name), dict(P=SPD3, name="P", rtol=1e-8),
                   dict(P="spd", name="instance_str", rtol="nonneg")))
    s.append(S("check_psd", C.check_psd, dict(Q=SPD3, name="Q", rtol=1e-8),
               dict(Q="psd", name="instance_str", rtol="nonneg")))
    s.append(S("logdet_spd", C.logdet_spd, dict(P=SPD3, name="P"), dict(P="spd", name="instance_str")))
    s.append(S("block_diag", C.block_diag, dict(blocks=[SPD3, np.eye(2)]), dict(blocks="iterable")))
    s.append(S("state_covariance", C.state_covariance, dict(sigma_pos_km=100.0, sigma_vel_km_s=1e-2, system=em),
               dict(sigma_pos_km="pos", sigma_vel_km_s="pos", system="system")))
    s.append(S("augment_states", C.augment_states, dict(observer=X_DRO, targets=np.array([X_DRO, X_DRO])),
               dict(observer="state", targets="arr")))
    s.append(S("augmented_covariance", C.augmented_covariance, dict(P_observer=SPD6, P_targets=SPD6),
               dict(P_observer="spd", P_targets="spd")))
    s.append(S("psd_to_nondimensional", C.psd_to_nondimensional, dict(q_km2_s3=1e-11, system=em),
               dict(q_km2_s3="nonneg", system="system")))
    A6 = em.jacobian(X_DRO)
    s.append(S("van_loan", C.van_loan, dict(A=A6, q=1e-3, dt=0.01), dict(A="arr", q="nonneg", dt="pos")))
    s.append(S("process_noise", C.process_noise,
               dict(system=em, x=lazy(_x_ballistic), t=T3, q=1e-6, n_nodes=4),
               dict(system="system", x="arr", t="grid", q="nonneg", n_nodes="int2")))
    s.append(S("process_noise_lyapunov", C.process_noise_lyapunov,
               dict(system=em, x0=X_DRO, dt=0.01, q=1e-6, rtol=1e-10, atol=1e-14),
               dict(system="system", x0="state", dt="pos", q="nonneg", rtol="range:1e-16:1e-2",
                    atol="range:1e-20:1e-2")))
    s.append(S("ekf_predict", C.ekf_predict, dict(P=SPD3, F=np.eye(3) * 1.1, Q=np.eye(3) * 0.1),
               dict(P="spd", F="arr", Q="psd")))
    s.append(S("ekf_update", C.ekf_update, dict(P=SPD3, H=np.ones((2, 3)), R=np.diag([0.5, 0.4])),
               dict(P="spd", H="arr", R="spd")))
    s.append(S("covariance_analysis", C.covariance_analysis, dict(lin), dict(LIN_KINDS)))
    s.append(S("position_sigma_km", C.position_sigma_km, dict(P=np.eye(12) * 1e-6, index=1, system=em, axes=(0, 1)),
               dict(P="psd", index="int0", system="system", axes="iterable")))
    s.append(S("propagate_arcs", C.propagate_arcs, dict(system=em, x0=X_DRO, t=T3, q=1e-10, order=1, n_nodes=4),
               dict(system="system", x0="state", t="grid", q="nonneg_opt", order="choice", n_nodes="int2")))
    s.append(S("assemble_augmented", C.assemble_augmented,
               dict(model=AZIMUTH_ELEVATION, noise=np.eye(2) * 1e-8, P0=np.eye(12) * 1e-6,
                    observer=lazy(lambda: _arcs()[0]), targets=lazy(lambda: _arcs()[1]), Q=np.eye(12) * 1e-12,
                    index=0),
               dict(model="instance", noise="spd", P0="spd", observer="instance", targets="instance", Q="psd_opt",
                    index="int0")))
    s.append(S("linearize_augmented", C.linearize_augmented,
               dict(system=em, observer_x0=X_DRO, targets_x0=np.array([[1.1, 0.0, 0.0, 0.0, -0.2, 0.0]]), t=T3,
                    model=AZIMUTH_ELEVATION, noise=np.eye(2) * 1e-8, P0=np.eye(12) * 1e-6, q=None,
                    Q=np.eye(12) * 1e-12, derivatives=False, n_nodes=4),
               dict(system="system", observer_x0="state", targets_x0="arr", t="grid", model="instance",
                    noise="spd", P0="spd", Q="psd_opt", derivatives="bool", n_nodes="int2")))
    s.append(S("WindowAssembler", C.WindowAssembler,
               dict(model=AZIMUTH_ELEVATION, noise=np.eye(2) * 1e-8, P0=np.eye(12) * 1e-6,
                    targets=lazy(lambda: _arcs()[1]), Q=np.eye(12) * 1e-12),
               dict(model="instance", noise="spd", P0="spd", targets="instance", Q="psd_opt")))
    s.append(S("WindowAssembler.__call__", lazy(_assembler), dict(observer=lazy(lambda: _arcs()[0]), index=0),
               dict(observer="instance", index="int0")))

    # ------------------------------------------------------------------------------------------ information
    I = information  # noqa: E741
    s.append(S("stacked_matrices", I.stacked_matrices, dict(lin), dict(LIN_KINDS)))
    s.append(S("stacked_derivative", I.stacked_derivative, dict(F=lin["F"], H=lin["H"], **der),
               dict(F="arr", H="arr", **DER_KINDS)))
    s.append(S("mutual_information_dense", I.mutual_information_dense, dict(lin), dict(LIN_KINDS)))
    s.append(S("mutual_information", I.mutual_information, dict(lin, return_terms=True),
               dict(LIN_KINDS, return_terms="bool")))
    s.append(S("mutual_information_gradient_dense", I.mutual_information_gradient_dense, dict(lin, **der),
               dict(LIN_KINDS, **DER_KINDS)))
    s.append(S("mutual_information_gradient", I.mutual_information_gradient, dict(lin, **der, method="sqrt"),
               dict(LIN_KINDS, **DER_KINDS, method="choice")))
    s.append(S("InformationKernel", I.InformationKernel,
               dict(P0=lin["P0"], Q=lin["Q"], R=lin["R"], n_times=lin["H"].shape[0], one_qr=True),
               dict(P0="spd", Q="psd", R="spd", n_times="int1", one_qr="bool")))
    kernel = lazy(lambda: I.InformationKernel(lin["P0"], lin["Q"], lin["R"], lin["H"].shape[0]))
    s.append(S("InformationKernel.value", lazy(lambda: kernel().value), dict(F=lin["F"], H=lin["H"]),
               dict(F="arr", H="arr")))
    s.append(S("InformationKernel.value_gradient", lazy(lambda: kernel().value_gradient),
               dict(F=lin["F"], H=lin["H"], **der), dict(F="arr", H="arr", **DER_KINDS)))
    s.append(S("window_information", I.window_information, dict(lin=lazy(_lin), method="structured", gradient=True),
               dict(lin="instance", method="choice", gradient="bool")))
    s.append(S("gaussian_kl", I.gaussian_kl, dict(mean_p=np.zeros(3), cov_p=SPD3, mean_q=np.ones(3),
                                                   cov_q=2.0 * SPD3),
               dict(mean_p="arr", cov_p="spd", mean_q="arr", cov_q="spd")))
    s.append(S("monte_carlo_mutual_information", I.monte_carlo_mutual_information,
               dict(lin, n_samples=4, rng=rng), dict(LIN_KINDS, n_samples="int2", rng="rng")))
    s.append(S("time_evaluations", I.time_evaluations, dict(lin, **der, repeat=1, min_time=1e-4),
               dict(LIN_KINDS, **DER_KINDS, repeat="int1", min_time="pos")))

    # --------------------------------------------------------------------------------------- discretization
    D = discretization
    s.append(S("sundman_nodes", D.sundman_nodes, dict(system=em, x0=X_DRO, t_final=0.1, n_nodes=3, sigma=1.0,
                                                       tol=1e-12),
               dict(system="system", x0="state", t_final="pos", n_nodes="int2", sigma="range:-3:3",
                    tol="range:1e-16:1e-3")))
    s.append(S("max_control_per_node", D.max_control_per_node, dict(t_nodes=T3, a_max=1e-3),
               dict(t_nodes="grid", a_max="nonneg")))
    s.append(S("FOHModel.predict", lazy(lambda: _foh_model().predict),
               dict(x_nodes=lazy(_x_ballistic), u_nodes=np.zeros((3, 3)), eps=np.zeros((2, 6))),
               dict(x_nodes="arr", u_nodes="arr", eps="arr_opt")))
    s.append(S("foh_discretize", D.foh_discretize,
               dict(system=em, t_nodes=T3, x_nodes=lazy(_x_ballistic), u_nodes=np.zeros((3, 3)), tol=1e-12),
               dict(system="system", t_nodes="grid", x_nodes="arr", u_nodes="arr", tol="range:1e-16:1e-3")))
    s.append(S("propagate_foh", D.propagate_foh,
               dict(system=em, x0=X_DRO, t_nodes=T3, u_nodes=np.zeros((3, 3)), tol=1e-12),
               dict(system="system", x0="state", t_nodes="grid", u_nodes="arr", tol="range:1e-16:1e-3")))

    # ------------------------------------------------------------------------------------------------- scvx
    settings_kinds = dict(method="choice", information_model="choice", rho0="range:0:1", rho1="range:0:1",
                          rho2="range:0:1", beta_shrink="pos", beta_grow="pos", eta0="pos", eta_min="pos",
                          eta_max="pos", defect_weight="pos", penalty_weight0="pos", penalty_weight_max="pos",
                          penalty_growth="pos", multiplier_threshold0="pos", multiplier_threshold_decay="range:0:1",
                          max_iter="int1", tol="pos", defect_tol="pos", active_tol="range:0:1", noise_tol="nonneg",
                          solver_tol="pos", hessian_step="pos", hessian_refresh="nonneg", hessian_error_ratio="pos",
                          stall_iter="int0", curvature_floor="nonneg")
    import dataclasses

    defaults = {f.name: f.default for f in dataclasses.fields(scvx.SCvxSettings)}
    assert set(defaults) == set(settings_kinds), "SCvxSettings fields changed: update the spec"
    s.append(S("SCvxSettings", scvx.SCvxSettings, defaults, settings_kinds))
    s.append(S("solve_scvx", scvx.solve_scvx,
               dict(system=em, t_nodes=T3, x_guess=lazy(_x_ballistic), u_guess=np.zeros((3, 3)),
                    u_max=np.full(3, 1e-3), x_final=None, info=None, info_node=None, constraints=(), alpha=0.0,
                    settings=None, solver="CLARABEL", progress=False, workspace=None),
               dict(system="system", t_nodes="grid", x_guess="arr", u_guess="arr", u_max="arr",
                    x_final="state_opt", info="callable_opt", info_node="int0_opt", constraints="instance_opt",
                    alpha="range:0:1", settings="instance_opt", solver="choice", progress="bool",
                    workspace="instance_opt")))
    s.append(S("SCvxWorkspace", scvx.SCvxWorkspace, dict(max_problems=4), dict(max_problems="int1")))
    s.append(S("concave_part", scvx.concave_part, dict(H=-SPD3, floor=0.0), dict(H="arr_finite", floor="nonneg")))
    s.append(S("finite_difference_hessian", scvx.finite_difference_hessian,
               dict(gradient=lambda x: 2.0 * np.asarray(x), x=np.array([0.1, 0.2]), step=1e-5, g0=None),
               dict(gradient="callable", x="vec", step="pos", g0="arr_opt")))
    s.append(S("homotopy_sweep", scvx.homotopy_sweep,
               dict(solve=_fake_solve, alphas=np.array([0.0, 0.5]), x_guess=lazy(_x_ballistic),
                    u_guess=np.zeros((3, 3)), directions=("up", "down"), progress=False),
               dict(solve="callable", alphas="vec", x_guess="arr", u_guess="arr", directions="iterable",
                    progress="bool")))
    s.append(S("SweepResult.column", lazy(lambda: _sweep().column), dict(name="impulse"), dict(name="choice")))
    s.append(S("impulse", scvx.impulse, dict(t=T3, u=np.ones((3, 3))), dict(t="grid", u="arr")))

    # -------------------------------------------------------------------------------------------- reference
    s.append(S("TableRow", reference.TableRow, dict(table=2, label="DRO", x0=0.8, vy0=0.52),
               dict(table="int1", label="instance_str", x0="real", vy0="real")))
    s.append(S("load_wolf_jones_table", reference.load_wolf_jones_table, dict(path=None),
               dict(path="instance_str_opt")))
    s.append(S("verify_table_row", reference.verify_table_row, dict(system=em, row=lazy(_table_row)),
               dict(system="system", row="instance")))
    s.append(S("rounding_bound", reference.rounding_bound, dict(system=em, check=lazy(_row_check), half_unit=5e-10),
               dict(system="system", check="instance", half_unit="pos")))

    # -------------------------------------------------------------------------------------------------- lpv
    s.append(S("CR3BPLPV", lpv.CR3BPLPV, dict(system=em), dict(system="system")))
    s.append(S("CR3BPLPV.planar", MODEL.planar, dict(state6=X_DRO), dict(state6="state")))
    s.append(S("CR3BPLPV.spatial", MODEL.spatial, dict(state4=S_PLANAR[0]), dict(state4="arr")))
    # rho, angles and measure take planar states (..., 4) or positions (..., 2): any such shape is valid, so the
    # shape cases are in tests/test_validation_estimation.py
    for meth in ("rho", "angles", "measure"):
        s.append(S(f"CR3BPLPV.{meth}", getattr(MODEL, meth), dict(state=S_PLANAR[0]), dict(state="arr_finite")))
    s.append(S("CR3BPLPV.f", MODEL.f, dict(state=S_PLANAR[0]), dict(state="arr")))
    s.append(S("CR3BPLPV.rho_from_angles", MODEL.rho_from_angles, dict(theta1=0.3, theta2=0.5),
               dict(theta1="arr_finite", theta2="arr_finite")))
    for meth in ("A", "b", "C", "d", "d_as_printed_eq23"):
        s.append(S(f"CR3BPLPV.{meth}", getattr(MODEL, meth), dict(rho=RHO2[0]), dict(rho="arr")))
    for meth in ("lpv_rhs", "lpv_measure"):
        s.append(S(f"CR3BPLPV.{meth}", getattr(MODEL, meth), dict(state=S_PLANAR[0], rho=RHO2[0]),
                   dict(state="arr", rho="arr_opt")))
    s.append(S("ParameterBox", lpv.ParameterBox,
               dict(lower=RHO2.min(axis=0), upper=RHO2.max(axis=0), names=lpv.RHO_NAMES, source="s"),
               dict(lower="arr", upper="arr", names="instance", source="instance_str")))
    s.append(S("ParameterBox.from_samples", lpv.ParameterBox.from_samples, dict(rho=RHO2, margin=0.1, source="s"),
               dict(rho="arr_finite", margin="nonneg", source="instance_str")))
    s.append(S("ParameterBox.vertices", lazy(lambda: _box().vertices), dict(free=[0]), dict(free="iterable_opt")))
    s.append(S("ParameterBox.sample", lazy(lambda: _box().sample), dict(n=3, rng=rng), dict(n="int1", rng="rng")))
    s.append(S("ParameterBox.contains", lazy(lambda: _box().contains), dict(rho=RHO2[0], rtol=1e-12),
               dict(rho="arr", rtol="nonneg")))
    s.append(S("resonant_orbit", lpv.resonant_orbit, dict(system=em, p=3, q=1, perigee_radius=0.2),
               dict(system="system", p="int2", q="int1", perigee_radius="range:0.05:0.9")))
    s.append(S("ResonantOrbit.sample", lazy(lambda: _resonant().sample), dict(n=3, periods=0.1),
               dict(n="int2", periods="pos")))
    dist = lpv.default_disturbance()
    s.append(S("PrecisionLMI", lpv.PrecisionLMI,
               dict(A_vertices=MODEL.A(RHO2), C_vertices=MODEL.C(RHO2), norm="h2", disturbance=dist,
                    Cz=np.eye(2, 4), objective="l1", eps=1e-8, sensors=[0, 1], pole_radius=None,
                    state_scale=np.ones(4), variable_scale=1.0, backend="direct"),
               dict(A_vertices="arr", C_vertices="arr", norm="choice", disturbance="instance", Cz="arr_opt",
                    objective="choice", eps="pos", sensors="iterable_opt", pole_radius="pos_opt",
                    state_scale="arr_opt", variable_scale="pos_opt", backend="choice")))
    s.append(S("PrecisionLMI.for_cr3bp", lpv.PrecisionLMI.for_cr3bp,
               dict(model=MODEL, vertices=RHO2, norm="h2", disturbance=dist, sensors=[0, 1]),
               dict(model="instance", vertices="arr", norm="choice", disturbance="instance_opt")))
    s.append(S("PrecisionLMI.rescaled", lazy(lambda: _lmi().rescaled), dict(variable_scale=1.0, state_scale=None),
               dict(variable_scale="pos", state_scale="arr_opt")))
    solve_kw = dict(gamma=0.0013, solver="CLARABEL", disturbance_scale=1.0, tol=None, sparsity_tol=1e-4)
    solve_kinds = dict(gamma="pos", solver="choice", disturbance_scale="nonneg", tol="pos_opt",
                       sparsity_tol="range:0:1")
    s.append(S("PrecisionLMI.solve", lazy(lambda: _lmi().solve), dict(solve_kw, retry=False),
               dict(solve_kinds, retry="bool")))
    s.append(S("PrecisionLMI.solve_once", lazy(lambda: _lmi().solve_once), dict(solve_kw), dict(solve_kinds)))
    s.append(S("ObserverDesign.noise_per_sample_deg", lazy(lambda: _design().noise_per_sample_deg), dict(dt=0.01),
               dict(dt="pos")))
    s.append(S("ObserverDesign.gain", lazy(lambda: _design().gain), dict(drop_unused=True),
               dict(drop_unused="bool")))
    s.append(S("design_observer", lpv.design_observer,
               dict(model=MODEL, vertices=RHO2, gamma=0.0013, norm="h2", solver="CLARABEL", sensors=[0, 1]),
               dict(model="instance", vertices="arr", gamma="pos", norm="choice", solver="choice")))
    s.append(S("precision_to_noise_deg", lpv.precision_to_noise_deg, dict(kappa=np.array([2.0, 0.5])),
               dict(kappa="arr_any")))
    s.append(S("noise_deg_to_precision", lpv.noise_deg_to_precision, dict(noise_deg=np.array([0.1, 1.0])),
               dict(noise_deg="arr_finite")))
    A2 = np.array([[-1.0, 0.5], [0.0, -2.0]])
    B2 = np.array([[1.0, 0.0], [0.5, 1.0]])
    C2 = np.array([[1.0, 0.0]])
    s.append(S("h2_norm", lpv.h2_norm, dict(A=A2, B=B2, C=C2), dict(A="arr", B="arr_finite", C="arr")))
    s.append(S("hinf_norm", lpv.hinf_norm, dict(A=A2, B=B2, C=C2, rtol=1e-9, max_iter=50),
               dict(A="arr", B="arr_finite", C="arr", rtol="pos", max_iter="int1")))
    s.append(S("verify_observer", lpv.verify_observer,
               dict(model=MODEL, design=lazy(_design), box=lazy(_box), n_samples=1, rng=rng, L=None),
               dict(model="instance", design="instance", box="instance", n_samples="int1", rng="rng",
                    L="arr_opt")))
    s.append(S("gamma_sweep", lpv.gamma_sweep, dict(lmi=lazy(_lmi), gammas=np.array([0.0013]), solver="CLARABEL"),
               dict(lmi="instance", gammas="vec", solver="choice")))
    s.append(S("default_disturbance", lpv.default_disturbance, dict(sigma_acc=1e-3), dict(sigma_acc="nonneg")))
    s.append(S("error_system", lpv.error_system, dict(model=MODEL, design=lazy(_design), rho=RHO2[0], L=None),
               dict(model="instance", design="instance", rho="arr", L="arr_opt")))
    s.append(S("paper_scenario", nb_scenarios.paper_scenario,
               dict(system=em, p=2, q=1, perigee_radius=0.3, n_samples=10, margin=0.0),
               dict(system="system", p="int2", q="int1", perigee_radius="range:0.05:0.9", n_samples="int2",
                    margin="nonneg")))
    s.append(S("disturbance_model", lpv.disturbance_model, dict(structure="state", level=1e-3),
               dict(structure="choice", level="nonneg")))
    s.append(S("guaranteed_error_rms", lpv.guaranteed_error_rms, dict(design=lazy(_design), noise_rms_deg=0.1,
                                                                       dt=0.01),
               dict(design="instance", noise_rms_deg="nonneg", dt="pos_opt")))
    s.append(S("SensitivityStudy.h2_per_sample_deg", lazy(lambda: _study().h2_per_sample_deg),
               dict(dt=np.array([0.01, 0.02])), dict(dt="arr_finite")))
    s.append(S("SensitivityStudy.dt_for_h2", lazy(lambda: _study().dt_for_h2), dict(target_deg=0.1),
               dict(target_deg="range:0:90")))
    s.append(S("sensitivity_study", nb_sensing.sensitivity_study,
               dict(gamma=0.0013, orbits=((2, 1, 0.3),), structures=("acceleration",), levels=(1e-3,),
                    pole_radius=1000.0, n_samples=10, system=em, executor=None, progress=False),
               dict(gamma="pos", orbits="iterable", structures="choice", levels="vec", pole_radius="pos",
                    n_samples="int2", system="system", executor="instance_opt", progress="bool")))

    # -------------------------------------------------------------------------------------------- observers
    O = observers  # noqa: E741
    s.append(S("Measurements", O.Measurements,
               dict(t=T_OBS, theta1=np.full(4, 0.3), theta2=np.full(4, 0.5), sigma=0.01),
               dict(t="grid", theta1="arr", theta2="arr", sigma="nonneg")))
    s.append(S("make_measurements", O.make_measurements,
               dict(model=MODEL, t=T_OBS, truth=_truth(), sigma_deg=0.01, rng=rng),
               dict(model="instance", t="grid", truth="arr", sigma_deg="nonneg", rng="rng")))
    s.append(S("simulate_lpv_observer", O.simulate_lpv_observer,
               dict(model=MODEL, L=np.zeros((4, 6)), meas=lazy(_meas), x_hat0=_truth()[0], truth=_truth(),
                    sin3_threshold=0.04, substeps=2, exact_rho=False, hold="noise"),
               dict(model="instance", L="arr", meas="instance", x_hat0="arr", truth="arr",
                    sin3_threshold="range:0:1", substeps="int1_opt", exact_rho="bool", hold="choice")))
    s.append(S("simulate_ekf", O.simulate_ekf,
               dict(model=MODEL, meas=lazy(_meas), x_hat0=_truth()[0], P0=np.eye(4) * 1e-6, truth=_truth(),
                    sigma_acc=1e-3, substeps=2),
               dict(model="instance", meas="instance", x_hat0="arr", P0="spd", truth="arr", sigma_acc="nonneg",
                    substeps="int1")))
    return s

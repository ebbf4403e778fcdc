"""Mutual information + gradient at Wolf & Jones test-case-2 size: dense (Eqs. 18, 47-50) vs structured (chain rule).

Scenario: observer and three targets on the Table 4 DROs (observer on the ``observer_tf`` DRO, which closes; the
printed ``observer_t0`` row does not), range and range-rate measurements (100 m, 10 m/s), process-noise PSD
1e-11 LU^2/TU^3 (the adopted reading of Table 5), initial 100 km / 1 cm/s per axis, one measurement per day over the
observation window [P_ref, 2 P_ref] (17 measurement times, 24 states, 6 measurements per time: range and range rate
of 3 targets), derivatives with respect to the six observer coordinates.

One interleaved best-of-9 run times: the dense value and value + gradient; the structured value; the structured
value + gradient by reverse mode (``method="sqrt"``, the default), with the process-noise square roots cached as in
every repeated evaluation of one window (SCvx) and cold (cache cleared before each call); and by forward mode
(``method="sqrt-forward"``, the 2026-11-22 default); and the covariance-form adjoint (``method="adjoint"``, ~1e-5
relative error; its 2026-11-21 version, with a covariance-form forward pass, gave the 10x of that day), a reference
for ratios measured under different machine load.  Then the SCvx planning model of test case 2.

Then **old path vs new at both test-case sizes** (:func:`window_kernel`), in one interleaved run: the dense
reference; the public ``mutual_information_gradient`` as the SCvx information model called it before 2026-11-26
(every call re-checks F, H, dF, dH and looks P0, Q, R up in the module's checked-noise cache, the noise roots in
its root cache); and :class:`cislunar.sensing.information.InformationKernel`, which the information model now
builds once per window (P0, Q, R checked, R factored and Q's square roots taken once; bit-for-bit the same value
and gradient); and the kernel with ``one_qr=True`` (time and measurement updates in one QR per time; gradient not
bit for bit).  Test-case-2 size is the window above; test-case-1 size is the window of
:func:`cislunar.papers.wolf_jones.scenarios.test_case_1` (observer and one target, relative position, 13 daily
epochs, 12 states).

``python -m benchmarks information`` prints the times per evaluation and the ratios; ``main()`` returns them.
"""

from __future__ import annotations

import time

import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON
from cislunar.cr3bp.propagation import find_events, propagate
from cislunar.sensing import covariance as C
from cislunar.sensing import information as I
from cislunar.sensing import measurements as M

OBSERVER = np.array([7.80136159e-1, 0, 0, 0, 5.53104815e-1, 0])
TARGETS = np.array([[7.78717734e-1, 0, 0, 0, 5.55157488e-1, 0],
                    [7.79426943e-1, 0, 0, 0, 5.54128887e-1, 0],
                    [7.81554639e-1, 0, 0, 0, 5.51070308e-1, 0]])


def build_window(system=EARTH_MOON):
    """Linearisation of the test-case-2-sized window (with derivatives) and the reference period (TU)."""
    period = float(find_events(system, OBSERVER, 10.0, ("y_crossing",)).t[1])
    start = propagate(system, np.vstack([OBSERVER, TARGETS]), np.array([0.0, period])).x[:, -1]
    day = float(system.days_to_tu(1.0))
    t = period + np.arange(0.0, period + 1e-12, day)
    P0 = C.block_diag([C.state_covariance(C.WOLF_JONES_SIGMA_POS_KM, C.WOLF_JONES_SIGMA_VEL_KM_S, system)] * 4)
    R = M.range_range_rate_noise(M.WOLF_JONES_RANGE_SIGMA_KM, M.WOLF_JONES_RANGE_RATE_SIGMA_KM_S, system)
    q = C.psd_to_nondimensional(C.WOLF_JONES_PSD_KM2_S3, system)
    lin = C.linearize_augmented(system, start[0], start[1:], t, M.RANGE_RANGE_RATE, R, P0, q=q, derivatives=True)
    return lin, period


def _rel(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - b)) / np.max(np.abs(b)))


def main() -> dict:
    t0 = time.perf_counter()
    lin, period = build_window()
    t_build = time.perf_counter() - t0
    arrays = lin.arrays
    args = (*arrays, lin.dF, lin.dH)
    info_d, grad_d = I.mutual_information_gradient_dense(*args)
    info_s, grad_s = I.mutual_information_gradient(*args)
    _, grad_f = I.mutual_information_gradient(*args, method="sqrt-forward")
    _, grad_a = I.mutual_information_gradient(*args, method="adjoint")

    def cold():
        I._ROOT_CACHE.clear()
        return I.mutual_information_gradient(*args)

    names = ["dense_value", "structured_value", "dense_value_grad", "sqrt_reverse_value_grad",
             "sqrt_reverse_cold_value_grad", "sqrt_forward_value_grad", "covariance_adjoint_value_grad"]
    times = I._interleaved_best([
        lambda: I.mutual_information_dense(*arrays),
        lambda: I.mutual_information(*arrays),
        lambda: I.mutual_information_gradient_dense(*args),
        lambda: I.mutual_information_gradient(*args),
        cold,
        lambda: I.mutual_information_gradient(*args, method="sqrt-forward"),
        lambda: I.mutual_information_gradient(*args, method="adjoint"),
    ], 9, 0.1)
    ms = dict(zip(names, 1e3 * np.array(times)))
    N, M_, n = lin.H.shape
    out = {
        "n_measurement_times": int(N),
        "state_dim": int(n),
        "measurements_per_time": int(M_),
        "period_days": float(EARTH_MOON.tu_to_days(period)),
        "mutual_information_nats": float(info_s),
        "value_bit_for_bit_structured": bool(info_s == I.mutual_information(*arrays)),
        "mi_rel_diff_dense_structured": float(abs(info_s - info_d) / abs(info_d)),
        "grad_rel_diff_dense_structured": _rel(grad_s, grad_d),
        "grad_rel_diff_sqrt_forward_reverse": _rel(grad_s, grad_f),
        "grad_rel_diff_adjoint_reverse": _rel(grad_s, grad_a),
        "linearisation_s": t_build,
        **{f"{k}_ms": float(v) for k, v in ms.items()},
        "ratio_value": ms["dense_value"] / ms["structured_value"],
        "ratio_value_grad": ms["dense_value_grad"] / ms["sqrt_reverse_value_grad"],
        "ratio_value_grad_cold": ms["dense_value_grad"] / ms["sqrt_reverse_cold_value_grad"],
        "ratio_forward_over_reverse": ms["sqrt_forward_value_grad"] / ms["sqrt_reverse_value_grad"],
        "ratio_value_grad_forward": ms["dense_value_grad"] / ms["sqrt_forward_value_grad"],
        "ratio_value_grad_adjoint": ms["dense_value_grad"] / ms["covariance_adjoint_value_grad"],
    }
    print(f"window: {N} measurement times x {M_} measurements, state dim {n}, P_ref = {out['period_days']:.3f} d")
    print(f"MI = {info_s:.6f} nats (gradient's value bit-for-bit mutual_information: "
          f"{out['value_bit_for_bit_structured']}); dense vs structured MI rel diff "
          f"{out['mi_rel_diff_dense_structured']:.1e}")
    print(f"gradient rel diff (max abs) of the reverse mode from: forward mode "
          f"{out['grad_rel_diff_sqrt_forward_reverse']:.1e}, dense {out['grad_rel_diff_dense_structured']:.1e}, "
          f"covariance adjoint {out['grad_rel_diff_adjoint_reverse']:.1e}")
    print(f"linearisation (propagation, STMs/STT, process noise; includes first-call compilation): {t_build:.2f} s")
    print(f"MI only      : dense {ms['dense_value']:.3f} ms, structured {ms['structured_value']:.3f} ms, "
          f"ratio {out['ratio_value']:.1f}x")
    print(f"MI + gradient: dense {ms['dense_value_grad']:.3f} ms, reverse mode {ms['sqrt_reverse_value_grad']:.3f} ms "
          f"(cold noise roots {ms['sqrt_reverse_cold_value_grad']:.3f} ms), forward mode "
          f"{ms['sqrt_forward_value_grad']:.3f} ms, covariance adjoint {ms['covariance_adjoint_value_grad']:.3f} ms")
    print(f"ratios: dense / reverse {out['ratio_value_grad']:.1f}x (cold {out['ratio_value_grad_cold']:.1f}x), "
          f"forward / reverse {out['ratio_forward_over_reverse']:.1f}x, dense / forward "
          f"{out['ratio_value_grad_forward']:.1f}x, dense / covariance adjoint "
          f"{out['ratio_value_grad_adjoint']:.1f}x")
    out.update(planning_model())
    out.update(window_kernel("case2", lin))
    out.update(window_kernel("case1", case1_window()))
    return out


def case1_window():
    """Linearisation (with derivatives) of test case 1's window along the ballistic observer."""
    from cislunar.papers.wolf_jones import scenarios as W
    sc = W.test_case_1()
    x = propagate(sc.system, sc.observer_x0, np.array([0.0, sc.window[0]])).x[-1]
    return sc.information_model().linearization(x, derivatives=True)


def window_kernel(label: str, lin) -> dict:
    """Dense vs the old public path vs the per-window kernel (value + gradient), interleaved best-of-9."""
    P0, F, Q, H, R = lin.arrays
    dF, dH = lin.dF, lin.dH
    kernel = I.InformationKernel(P0, Q, R, H.shape[0])
    kernel_1qr = I.InformationKernel(P0, Q, R, H.shape[0], one_qr=True)
    v_k, g_k = kernel.value_gradient(F, H, dF, dH)
    v_1, g_1 = kernel_1qr.value_gradient(F, H, dF, dH)
    v_p, g_p = I.mutual_information_gradient(P0, F, Q, H, R, dF, dH)
    v_d, g_d = I.mutual_information_gradient_dense(P0, F, Q, H, R, dF, dH)
    t_dense, t_public, t_kernel, t_value_public, t_value_kernel, t_1qr = I._interleaved_best([
        lambda: I.mutual_information_gradient_dense(P0, F, Q, H, R, dF, dH),
        lambda: I.mutual_information_gradient(P0, F, Q, H, R, dF, dH),
        lambda: kernel.value_gradient(F, H, dF, dH),
        lambda: I.mutual_information(P0, F, Q, H, R),
        lambda: kernel.value(F, H),
        lambda: kernel_1qr.value_gradient(F, H, dF, dH)], 9, 0.1)
    N, M_, n = H.shape
    p = f"{label}_kernel_"
    out = {p + "shape": (int(N), int(M_), int(n)), p + "bit_identical_to_public": bool(v_k == v_p and np.array_equal(g_k, g_p)),
           p + "grad_rel_diff_dense": _rel(g_k, g_d), p + "mi_rel_diff_dense": abs(v_k - v_d) / abs(v_d),
           p + "dense_value_grad_ms": 1e3 * t_dense, p + "public_value_grad_ms": 1e3 * t_public,
           p + "kernel_value_grad_ms": 1e3 * t_kernel, p + "public_value_ms": 1e3 * t_value_public,
           p + "kernel_value_ms": 1e3 * t_value_kernel,
           p + "ratio_dense_over_public": t_dense / t_public, p + "ratio_dense_over_kernel": t_dense / t_kernel,
           p + "ratio_public_over_kernel": t_public / t_kernel,
           p + "one_qr_value_grad_ms": 1e3 * t_1qr, p + "ratio_dense_over_one_qr": t_dense / t_1qr,
           p + "one_qr_grad_rel_diff": _rel(g_1, g_k), p + "one_qr_mi_rel_diff": abs(v_1 - v_k) / abs(v_k)}
    print(f"{label} size ({N} times x {M_} measurements, {n} states), MI + gradient: dense {1e3 * t_dense:.3f} ms, "
          f"old path (public, re-checking) {1e3 * t_public:.3f} ms, InformationKernel {1e3 * t_kernel:.3f} ms "
          f"(bit-identical to the old path: {out[p + 'bit_identical_to_public']}; gradient vs dense "
          f"{out[p + 'grad_rel_diff_dense']:.1e})")
    print(f"  ratios: dense / old {t_dense / t_public:.1f}x, dense / kernel {t_dense / t_kernel:.1f}x, old / kernel "
          f"{t_public / t_kernel:.2f}x; MI alone: old {1e3 * t_value_public:.3f} ms, kernel "
          f"{1e3 * t_value_kernel:.3f} ms")
    print(f"  one QR per time (InformationKernel(one_qr=True), not bit-identical): {1e3 * t_1qr:.3f} ms, dense / one-QR "
          f"{t_dense / t_1qr:.1f}x; gradient moves {out[p + 'one_qr_grad_rel_diff']:.1e} relative, MI "
          f"{out[p + 'one_qr_mi_rel_diff']:.1e}")
    return out


def planning_model() -> dict:
    """The SCvx information model of test case 2 (cislunar.papers.wolf_jones.scenarios): cost of value, gradient, Hessian.

    Ratios in one interleaved run: the reverse-mode square-root gradient (default) against the forward mode and the
    covariance-form adjoint.
    """
    from cislunar.papers.wolf_jones import scenarios as W
    sc = W.test_case_2()
    model = sc.information_model()
    x = propagate(sc.system, sc.observer_x0, np.array([0.0, sc.window[0]])).x[-1]
    lin = model.linearization(x, derivatives=True)
    args = (*lin.arrays, lin.dF, lin.dH)
    t_rev, t_fwd, t_adj = I._interleaved_best([
        lambda: I.mutual_information_gradient(*args),
        lambda: I.mutual_information_gradient(*args, method="sqrt-forward"),
        lambda: I.mutual_information_gradient(*args, method="adjoint")], 5, 0.1)
    t0 = time.perf_counter()
    model.hessian(x)
    t_hess = time.perf_counter() - t0
    v0 = model(x)
    v1, g = model(x, 1)
    g_fwd = I.mutual_information_gradient(*args, method="sqrt-forward")[1]
    out = {"tc2_gradient_sqrt_ms": 1e3 * t_rev, "tc2_gradient_sqrt_forward_ms": 1e3 * t_fwd,
           "tc2_gradient_adjoint_ms": 1e3 * t_adj, "tc2_gradient_ratio_forward_over_sqrt": t_fwd / t_rev,
           "tc2_gradient_ratio_sqrt_over_adjoint": t_rev / t_adj, "tc2_grad_rel_diff_forward": _rel(g, g_fwd),
           "tc2_hessian_incl_propagation_s": t_hess, "tc2_value_order0_vs_order1_rel": abs(v0 - v1) / abs(v0)}
    print(f"test case 2 planning model: gradient reverse {out['tc2_gradient_sqrt_ms']:.2f} ms, forward "
          f"{out['tc2_gradient_sqrt_forward_ms']:.2f} ms, covariance adjoint {out['tc2_gradient_adjoint_ms']:.2f} ms "
          f"(reverse vs forward gradient rel diff {out['tc2_grad_rel_diff_forward']:.1e}); central-difference Hessian "
          f"incl. propagation {t_hess:.2f} s; value(order 0) vs value(order 1) rel diff "
          f"{out['tc2_value_order0_vs_order1_rel']:.1e}")
    return out


if __name__ == "__main__":
    main()

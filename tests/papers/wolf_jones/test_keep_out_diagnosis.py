"""Test case 2 without a keep-out: the range-noise remedy's MI and gradient, and the close-pass growth it removes."""

from __future__ import annotations

import numpy as np
import pytest

from cislunar.cr3bp.propagation import propagate
from cislunar.papers.wolf_jones import keep_out_diagnosis as K
from cislunar.papers.wolf_jones import scenarios as wj


@pytest.fixture(scope="module")
def case2():
    sc = wj.test_case_2()
    info = sc.information_model()
    x_ws = propagate(sc.system, sc.observer_x0, [0.0, sc.window[0]]).x[-1]
    return sc, info, x_ws


def test_remedy_is_the_paper_mi_far_from_the_targets(case2):
    """rho_c far below every range: the row scale is 1 to ~1e-18, so value and gradient are the paper's."""
    sc, info, x_ws = case2
    tiny = K.RangeNoiseInformation(info, 1e-6)  # 1 mm, against ranges of ~1000 km
    v0, g0 = info(x_ws, 1)
    v1, g1 = tiny(x_ws, 1)
    assert v1 == pytest.approx(v0, rel=1e-9) and np.allclose(g1, g0, rtol=1e-7, atol=1e-9 * np.abs(g0).max())
    big = K.RangeNoiseInformation(info, 141.0)
    assert big(x_ws, 0) < v0  # more noise near the targets: less information


def test_remedy_gradient_matches_finite_differences_near_a_target(case2):
    """At a 50 km pass (well inside rho_c = 141 km, where the scale's derivative dominates), the remedy's gradient
    against fourth-order central differences of its value; the scale's derivative is needed to match."""
    sc, info, x_ws = case2
    remedy = K.RangeNoiseInformation(info, 141.0)
    lin0 = info.linearization(x_ws)
    j, k, _ = K._closest(lin0)
    x = K.passing_state(sc.system, [lin0.t[0], lin0.t[k]], lin0.targets[j, k, :3], 50.0, x_ws)
    _, g = remedy(x, 1)
    h = np.array([1e-7] * 3 + [1e-7] * 3)
    fd = np.zeros(6)
    for i in range(6):
        e = np.zeros(6)
        e[i] = h[i]
        fd[i] = (8 * (remedy(x + e) - remedy(x - e)) - (remedy(x + 2 * e) - remedy(x - 2 * e))) / (12 * h[i])
    scale = np.abs(fd).max()
    np.testing.assert_allclose(g, fd, rtol=2e-4, atol=2e-4 * scale)
    # the same pass with the paper's noise: a different gradient (the remedy is not a no-op there)
    assert np.abs(info(x, 1)[1] - g).max() > 0.1 * scale


def test_close_pass_growth_and_its_removal(case2):
    """Below 10 km the whitened range-rate row and the MI gradient grow like 1/rho (log-log slope -1 within 0.2)
    while the range row stays flat; with the range-dependent noise the gradient no longer grows."""
    sc, info, x_ws = case2
    d = np.array([0.3, 1.0, 3.0, 9.0])
    plain = K.pass_scan(sc, info, x_ws, d)
    assert plain.slope("range_rate_row") == pytest.approx(-1.0, abs=0.2)
    assert plain.slope("grad_position") == pytest.approx(-1.0, abs=0.2)
    assert abs(plain.slope("range_row")) < 0.05
    remedy = K.pass_scan(sc, K.RangeNoiseInformation(info, 141.0), x_ws, d)
    assert remedy.slope("grad_position") > -0.2
    assert remedy.grad_position[0] < 0.05 * plain.grad_position[0]


def test_bad_arguments_name_the_argument(case2):
    sc, info, x_ws = case2
    with pytest.raises(ValueError, match="range_scale_km"):
        K.RangeNoiseInformation(info, 0.0)
    with pytest.raises(TypeError, match="inner"):
        K.RangeNoiseInformation(lambda x, o=0: 0.0, 1.0)
    with pytest.raises(ValueError, match="d_km"):
        K.pass_scan(sc, info, x_ws, [1.0, -1.0])

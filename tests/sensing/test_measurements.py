"""Measurement models: values, analytic Jacobians vs finite differences, Hessians, degenerate geometry, noise."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cislunar.cr3bp.dynamics import EARTH_MOON
from cislunar.sensing import measurements as M

MODELS = list(M.MODELS.values())


def _random_pair(rng, shape=()):
    obs = rng.normal(size=shape + (6,))
    tgt = obs + rng.normal(size=shape + (6,))
    return obs, tgt


def _fd_jacobian(model, obs, tgt, wrt, h=1e-6):
    """Central differences of the (wrapped) measurement with respect to observer or target."""
    out = np.zeros(np.broadcast_shapes(obs.shape, tgt.shape)[:-1] + (model.dim, 6))
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        if wrt == "target":
            yp, ym = model(obs, tgt + e), model(obs, tgt - e)
        else:
            yp, ym = model(obs + e, tgt), model(obs - e, tgt)
        out[..., j] = model.residual(yp, ym) / (2 * h)
    return out


@pytest.mark.parametrize("model", MODELS, ids=lambda m: m.name)
def test_jacobians_match_finite_differences(model):
    rng = np.random.default_rng(1)
    obs, tgt = _random_pair(rng, (4, 3))
    _, Hs, Ht = model.evaluate(obs, tgt)
    assert Hs.shape == Ht.shape == (4, 3, model.dim, 6)
    np.testing.assert_allclose(Ht, _fd_jacobian(model, obs, tgt, "target"), rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(Hs, _fd_jacobian(model, obs, tgt, "observer"), rtol=1e-6, atol=1e-8)


@given(seed=st.integers(0, 2**32 - 1), scale=st.floats(1e-4, 1e2))
def test_jacobians_fd_over_scales(seed, scale):
    """Analytic Jacobians hold over ranges from 1e-4 to 1e2 (LU) with a relative step."""
    rng = np.random.default_rng(seed)
    obs = rng.normal(size=6)
    rel = rng.normal(size=6) * scale
    rel[:2] += np.sign(rel[:2]) * 0.1 * scale  # keep clear of the +-z pole where azimuth is undefined
    tgt = obs + rel
    for model in MODELS:
        _, _, Ht = model.evaluate(obs, tgt)
        h = 1e-6 * scale
        fd = _fd_jacobian(model, obs, tgt, "target", h=h)
        np.testing.assert_allclose(Ht, fd, rtol=2e-5, atol=1e-7 * np.max(np.abs(Ht)))


@pytest.mark.parametrize("model", MODELS, ids=lambda m: m.name)
def test_hessians_match_finite_differences_of_jacobian(model):
    rng = np.random.default_rng(2)
    obs, tgt = _random_pair(rng, (5,))
    hess = model.hessian(obs, tgt)
    fd = np.zeros_like(hess)
    h = 1e-6
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        fd[..., j] = (model.jacobians(obs, tgt + e)[1] - model.jacobians(obs, tgt - e)[1]) / (2 * h)
    np.testing.assert_allclose(hess, fd, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(hess, np.swapaxes(hess, -1, -2), atol=1e-12)


def test_rates_are_time_derivatives_of_angles_and_range():
    """Range rate and angle rates equal the position Jacobian applied to the relative velocity."""
    rng = np.random.default_rng(3)
    obs, tgt = _random_pair(rng, (7,))
    rel_v = (tgt - obs)[..., 3:6]
    _, _, J = M.range_range_rate(obs, tgt, jacobian=True)
    np.testing.assert_allclose(M.range_range_rate(obs, tgt)[..., 1], np.einsum("ij,ij->i", J[:, 0, :3], rel_v),
                               rtol=1e-12)
    _, _, Ja = M.azimuth_elevation(obs, tgt, jacobian=True)
    np.testing.assert_allclose(M.angle_rates(obs, tgt), np.einsum("imj,ij->im", Ja[..., :3], rel_v), rtol=1e-10)


def test_azimuth_elevation_jacobian_is_amos_eq18():
    rng = np.random.default_rng(4)
    obs, tgt = _random_pair(rng)
    rx, ry, rz = (tgt - obs)[:3]
    s = rx**2 + ry**2
    r2 = s + rz**2
    paper = np.array([[-ry / s, rx / s, 0, 0, 0, 0],
                      [-rx * rz / (r2 * np.sqrt(s)), -ry * rz / (r2 * np.sqrt(s)), np.sqrt(s) / r2, 0, 0, 0]])
    _, Hs, Ht = M.azimuth_elevation(obs, tgt, jacobian=True)
    np.testing.assert_allclose(Ht, paper, rtol=1e-13)
    np.testing.assert_allclose(Hs, -paper, rtol=1e-13)


def test_known_values():
    obs = np.zeros(6)
    assert M.range_range_rate(obs, [3, 4, 0, 1, 0, 0]) == pytest.approx([5.0, 0.6])
    np.testing.assert_allclose(M.azimuth_elevation(obs, [0, 2, 0, 0, 0, 0]), [np.pi / 2, 0.0])
    np.testing.assert_allclose(M.azimuth_elevation(obs, [1, 0, 1, 0, 0, 0]), [0.0, np.pi / 4])
    # circular motion about the observer in the x-y plane at unit angular rate
    np.testing.assert_allclose(M.angle_rates(obs, [2, 0, 0, 0, 2, 0]), [1.0, 0.0])
    np.testing.assert_allclose(M.relative_position([1, 1, 1, 0, 0, 0], [2, 3, 4, 0, 0, 0]), [1, 2, 3])
    # observer and target swapped: relative position flips sign
    np.testing.assert_allclose(M.relative_state([1, 2, 3, 4, 5, 6], obs), -np.arange(1, 7))


def test_vectorised_over_leading_axes_and_broadcasting():
    rng = np.random.default_rng(5)
    obs = rng.normal(size=(4, 6))
    tgts = obs[None] + rng.normal(size=(3, 4, 6))
    for model in MODELS:
        val, Hs, Ht = model.evaluate(obs, tgts)
        assert val.shape == (3, 4, model.dim)
        for i in range(3):
            for j in range(4):
                v1, hs1, ht1 = model.evaluate(obs[j], tgts[i, j])
                np.testing.assert_allclose(val[i, j], v1, rtol=1e-14)
                np.testing.assert_allclose(Ht[i, j], ht1, rtol=1e-14)


@pytest.mark.parametrize("model", [M.RANGE_RANGE_RATE, M.AZIMUTH_ELEVATION, M.ANGLE_RATES, M.ANGLES_AND_RATES],
                         ids=lambda m: m.name)
def test_zero_range_raises(model):
    obs = np.array([0.5, 0.1, 0.0, 0.0, 0.3, 0.0])
    tgt = obs.copy()
    tgt[3] += 1e-3  # same position, different velocity
    with pytest.raises(ValueError, match="coincide"):
        model.evaluate(obs, tgt)
    with pytest.raises(ValueError, match="coincide"):
        model.hessian(obs, tgt)


def test_relative_position_defined_at_zero_range():
    obs = np.array([0.5, 0.1, 0.0, 0.0, 0.3, 0.0])
    val, Hs, Ht = M.relative_position(obs, obs, jacobian=True)
    np.testing.assert_array_equal(val, 0.0)
    np.testing.assert_array_equal(Ht[:, :3], np.eye(3))


@pytest.mark.parametrize("model", [M.AZIMUTH_ELEVATION, M.ANGLE_RATES], ids=lambda m: m.name)
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_elevation_pole_raises(model, sign):
    obs = np.zeros(6)
    tgt = np.array([0.0, 0.0, sign * 0.2, 0.01, 0.0, 0.0])
    with pytest.raises(ValueError, match="elevation"):
        model.evaluate(obs, tgt)
    # just off the pole the value is fine and the elevation is close to +-90 deg
    tgt[0] = 1e-6
    az_el = M.azimuth_elevation(obs, tgt)
    assert az_el[1] == pytest.approx(sign * np.pi / 2, abs=1e-4)


def test_azimuth_wrap_and_residual():
    obs = np.zeros(6)
    eps = 1e-3
    above = M.azimuth_elevation(obs, [-1.0, eps, 0, 0, 0, 0])[0]
    below = M.azimuth_elevation(obs, [-1.0, -eps, 0, 0, 0, 0])[0]
    assert above == pytest.approx(np.pi - eps, rel=1e-6)
    assert below == pytest.approx(-np.pi + eps, rel=1e-6)
    res = M.AZIMUTH_ELEVATION.residual([above, 0.0], [below, 0.0])
    assert res[0] == pytest.approx(-2 * np.arctan(eps), rel=1e-9)  # not 2 pi - 2 eps: y from -eps to +eps at x < 0 turns clockwise
    # exactly on the negative x axis the azimuth is +pi (numpy's convention), residual to -pi is 0
    assert M.azimuth_elevation(obs, [-1.0, 0.0, 0, 0, 0, 0])[0] == pytest.approx(np.pi)
    assert M.wrap_angle(np.pi) == pytest.approx(-np.pi)
    # the Jacobian is continuous across the branch cut (wrapped finite differences agree)
    tgt = np.array([-1.0, 1e-9, 0.1, 0.0, 0.0, 0.0])
    _, _, Ht = M.azimuth_elevation(obs, tgt, jacobian=True)
    np.testing.assert_allclose(Ht, _fd_jacobian(M.AZIMUTH_ELEVATION, obs, tgt, "target", h=1e-7), atol=1e-6)
    # residual leaves non-angle components alone
    r = M.ANGLES_AND_RATES.residual([3.0, 3.0, 7.0, 7.0], [-3.0, -3.0, 0.0, 0.0])
    np.testing.assert_allclose(r, [6.0 - 2 * np.pi, 6.0, 7.0, 7.0])


def test_angular_noise_model_amos():
    # Eq. 20 and its limits
    assert M.angular_sigma(1.0, 1e-5, 0.0) == pytest.approx(1e-5)
    assert M.angular_sigma(0.004, 0.0, 0.004) == pytest.approx(1.0)
    rho = np.array([0.1, 0.215, 10.0, 1e4])  # km
    sig = M.angular_sigma(rho, M.AMOS_SIGMA_MIN_RAD, M.AMOS_RESOLUTION_KM)
    np.testing.assert_allclose(sig**2 * rho**2, rho**2 * 1e-10 + 0.004**2, rtol=1e-12)  # Eq. 19
    assert np.all(np.diff(sig) < 0) and sig[-1] == pytest.approx(1e-5, rel=1e-3)
    # rate noise of G&S 2021 Eq. 13
    assert M.angle_rate_sigma(1e-5, 1.0) == pytest.approx(np.sqrt(2) * 1e-5)
    obs = np.zeros(6)
    tgt = np.array([0.215 / EARTH_MOON.length_unit_km, 0, 0, 0, 0, 0])
    R = M.angles_noise(obs, tgt, EARTH_MOON, rate_dt_s=1.0)
    s = M.angular_sigma(0.215, 1e-5, 0.004)
    np.testing.assert_allclose(np.diag(R), [s**2, s**2, (np.sqrt(2) * s * EARTH_MOON.time_unit_s) ** 2,
                                           (np.sqrt(2) * s * EARTH_MOON.time_unit_s) ** 2], rtol=1e-12)
    assert M.angles_noise(np.zeros((3, 6)), np.ones((3, 6)), EARTH_MOON).shape == (3, 2, 2)


def test_wolf_jones_noise_units():
    R = M.range_range_rate_noise(M.WOLF_JONES_RANGE_SIGMA_KM, M.WOLF_JONES_RANGE_RATE_SIGMA_KM_S, EARTH_MOON)
    assert np.sqrt(R[0, 0]) * EARTH_MOON.length_unit_km == pytest.approx(0.1)
    assert np.sqrt(R[1, 1]) * EARTH_MOON.velocity_unit_km_s == pytest.approx(0.01)
    assert R[0, 1] == 0.0
    Rp = M.relative_position_noise(0.1, EARTH_MOON)
    np.testing.assert_allclose(Rp, np.eye(3) * (0.1 / 384400.0) ** 2)


@pytest.mark.parametrize("call, name", [
    (lambda: M.range_range_rate(np.zeros(5), np.ones(6)), "observer"),
    (lambda: M.range_range_rate(np.zeros(6), np.ones((2, 7))), "target"),
    (lambda: M.range_range_rate(np.zeros((3, 6)), np.ones((2, 6))), "broadcast"),
    (lambda: M.range_range_rate(np.zeros(6), [np.nan] * 6), "target"),
    (lambda: M.angular_sigma(-1.0, 1e-5, 0.004), "range_"),
    (lambda: M.angular_sigma(1.0, -1e-5, 0.004), "sigma_min"),
    (lambda: M.angular_sigma(1.0, 1e-5, -0.004), "resolution"),
    (lambda: M.angle_rate_sigma(-1.0, 1.0), "sigma_angle"),
    (lambda: M.angle_rate_sigma(1.0, 0.0), "dt"),
    (lambda: M.range_range_rate_noise(-0.1, 0.01, EARTH_MOON), "sigma_range_km"),
    (lambda: M.range_range_rate_noise(0.1, 0.01, "earth"), "system"),
    (lambda: M.relative_position_noise(0.0, EARTH_MOON), "sigma_km"),
    (lambda: M.diagonal_covariance([1.0, -2.0]), "sigmas"),
    (lambda: M.RANGE_RANGE_RATE.residual([1.0, 2.0, 3.0], [1.0, 2.0]), "y"),
])
def test_bad_input_names_argument(call, name):
    with pytest.raises(ValueError, match=name):
        call()

"""Boundary checks of the estimation modules that the table sweep (tests/reliability_specs_estimation.py) cannot
express: shapes of arguments whose valid shapes vary, impacts on integration paths, and the junk cases of issue 11."""

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import ImpactError
from cislunar.estimation import lpv, observers
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import reference
from cislunar.sensing import covariance as C
from cislunar.sensing import information

MODEL = lpv.CR3BPLPV()
MU = em.mu


@pytest.mark.parametrize("bad", [np.ones((2, 3)), np.ones(3), np.ones((0, 0)), np.ones((2, 0, 0))])
def test_square_matrix_arguments_refuse_other_shapes(bad):
    with pytest.raises(ValueError, match="^P0"):
        C.symmetrize(bad, "P0")
    with pytest.raises(ValueError, match="^H"):
        scvx.concave_part(bad)


@pytest.mark.parametrize("meth", ["rho", "angles", "measure"])
@pytest.mark.parametrize("bad", [np.ones(3), np.ones((2, 5)), np.ones((0, 4)), np.ones((2, 2, 2, 4))])
def test_planar_state_arguments_refuse_other_shapes(meth, bad):
    with pytest.raises(ValueError, match="^state"):
        getattr(MODEL, meth)(bad)
    # positions (..., 2) and planar states (..., 4) are both valid and agree
    s = np.array([[-0.3, 0.05, 0.1, -1.5]])
    a, b = getattr(MODEL, meth)(s), getattr(MODEL, meth)(s[:, :2])
    assert np.allclose(a, b)


def test_lyapunov_process_noise_refuses_impacts():
    r = em.secondary_radius
    inside = np.array([1 - MU + 0.5 * r, 0, 0, 0, 0, 0])
    diving = np.array([1 - MU + 3 * r, 0, 0, -0.5, 0, 0])  # reaches the surface after ~0.009 TU
    with pytest.raises(ImpactError, match="starts inside the Moon"):
        C.process_noise_lyapunov(em, inside, 0.1, 1e-6)
    with pytest.raises(ImpactError, match="Moon's surface") as info:
        C.process_noise_lyapunov(em, diving, 0.1, 1e-6)
    assert 0.0 < info.value.time < 0.02
    # the same arc short of the surface is computed (and agrees with the quadrature form)
    Q = C.process_noise_lyapunov(em, diving, 0.005, 1e-6)
    Qq = C.process_noise(em, np.array([diving, diving]), np.array([0.0, 0.005]), 1e-6)[0]
    assert np.allclose(Q, Qq, rtol=1e-8, atol=1e-20)


def test_scvx_refuses_a_guess_through_a_primary():
    t = np.array([0.0, 0.05, 0.1])
    x = np.tile([0.8, 0, 0, 0, 0.52, 0], (3, 1))
    x[1, :3] = [1 - MU, 0.0, 0.0]  # the Moon's centre
    with pytest.raises(ValueError, match="^x_guess holds a state inside a primary"):
        scvx.solve_scvx(em, t, x, np.zeros((3, 3)), np.full(3, 1e-3))


def test_position_sigma_refuses_a_negative_covariance():
    P = np.eye(12) * 1e-6
    assert C.position_sigma_km(P, 1, em) == pytest.approx(np.sqrt(3e-6) * em.length_unit_km)
    with pytest.raises(ValueError, match="^P must be positive semi-definite"):
        C.position_sigma_km(-P, 1, em)  # was NaN
    with pytest.raises(ValueError, match="^index"):
        C.position_sigma_km(P, 2, em)


def test_block_diag_names_the_offending_block_and_keeps_a_single_matrix():
    with pytest.raises(ValueError, match=r"^blocks\[1\] must be a square matrix"):
        C.block_diag([np.eye(2), np.ones((2, 3))])
    with pytest.raises(TypeError, match="^blocks"):
        C.block_diag(None)
    A = np.array([[1.0, 2.0], [3.0, 4.0]])
    assert np.array_equal(C.block_diag(A), A)  # was split into its rows
    assert np.array_equal(C.block_diag([1.0, 2.0]), np.diag([1.0, 2.0]))


def test_derivative_shapes_name_both_arguments():
    F = np.tile(np.eye(2), (2, 1, 1))
    H = np.ones((3, 1, 2))
    with pytest.raises(ValueError, match="dF and dH"):
        information.stacked_derivative(F, H, np.zeros((2, 2, 2, 3)), np.zeros((3, 1, 2, 2)))
    with pytest.raises(ValueError, match="^dH must hold at least one parameter"):
        information.stacked_derivative(F, H, np.zeros((2, 2, 2, 0)), np.zeros((3, 1, 2, 0)))


def test_input_records_validate_their_fields():
    with pytest.raises(TypeError, match="^table"):
        reference.TableRow("2", "DRO", 0.8, 0.5)
    with pytest.raises(ValueError, match="^vy0"):
        reference.TableRow(2, "DRO", 0.8, float("nan"))
    t = np.array([0.0, 0.1, 0.2])
    with pytest.raises(ValueError, match="^theta2 must have shape"):
        observers.Measurements(t, np.zeros(3), np.zeros(2), 0.0)
    with pytest.raises(ValueError, match="^sigma"):
        observers.Measurements(t, np.zeros(3), np.zeros(3), -1.0)
    # a box over four parameters gets generic names rather than a mismatch with RHO_NAMES
    box = lpv.ParameterBox.from_samples(np.array([[0.0, 1.0, 2.0, 3.0], [1.0, 2.0, 3.0, 4.0]]))
    assert box.names == ("rho_1", "rho_2", "rho_3", "rho_4")
    with pytest.raises(ValueError, match="^lower and upper"):
        lpv.ParameterBox(np.zeros(5), np.ones(6))


def test_callables_returning_junk_are_named():
    with pytest.raises(ValueError, match=r"^gradient\(x\) must have shape"):
        scvx.finite_difference_hessian(lambda x: np.ones(3), np.zeros(2))
    with pytest.raises(ValueError, match=r"^gradient\(x\) contains NaN"):
        scvx.finite_difference_hessian(lambda x: np.full(2, np.nan), np.zeros(2))
    x = np.tile([0.8, 0, 0, 0, 0.52, 0], (3, 1))
    with pytest.raises(TypeError, match=r"^solve\(alpha, x_guess, u_guess\) result"):
        scvx.homotopy_sweep(lambda a, x, u: {"cost": 0.0}, [0.0, 0.5], x, np.zeros((3, 3)))

"""Filter consistency: the normalised estimation error squared (NEES) and its chi-square limit.

One home for the NEES used by every estimator test and study of the package (single runs, stacked Monte Carlo
trials, adaptive OCBE panels).
"""

from __future__ import annotations

import numpy as np
from scipy.stats import chi2

from cislunar.utils import validation

__all__ = ["NEES_PROBABILITY", "nees", "nees_limit"]

#: NEES threshold probability: an epoch is inconsistent when the 6-dof NEES exceeds its 99.9% chi-square quantile.
NEES_PROBABILITY = 0.999


def nees_limit(dof: int = 6, probability: float = NEES_PROBABILITY) -> float:
    """Chi-square quantile above which one epoch's NEES counts as inconsistent (dimensionless).

    Parameters
    ----------
    dof : int
        Degrees of freedom (the state dimension, >= 1).
    probability : float
        Quantile, in (0, 1).
    """
    dof = validation.integer(dof, "dof", minimum=1)
    probability = validation.in_range(probability, "probability", 0.0, 1.0, closed=False)
    return float(chi2.ppf(probability, dof))


def nees(x_est, P, truth) -> np.ndarray:
    """Normalised estimation error squared :math:`e^\\top P^{-1}e` per epoch, shape (N,)."""
    x_est = validation.as_array(x_est, "x_est", ndim=(1, 2), last=6)
    truth = validation.as_array(truth, "truth", shape=x_est.shape)
    e = np.atleast_2d(x_est - truth)
    P = validation.spd(P, "P", n=6, batch=True)
    P = P.reshape(-1, 6, 6)
    if P.shape[0] != e.shape[0]:
        raise ValueError(f"P must have one 6x6 covariance per epoch ({e.shape[0]}); got shape {P.shape}")
    out = np.einsum("ni,ni->n", e, np.linalg.solve(P, e[..., None])[..., 0])
    return out if x_est.ndim == 2 else out[0]


def _nees(x, P, truth) -> np.ndarray:
    """Stacked NEES ``e^T P^-1 e`` over the last two axes (unchecked kernel: internal, finite inputs)."""
    e = x - truth
    return np.einsum("...i,...i->...", e, np.linalg.solve(P, e[..., None])[..., 0])

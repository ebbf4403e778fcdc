r"""The set-up of this reproduction of Nychka & Bhattacharya (arXiv 2410.02013): bound, sensors, orbit, polytope.

The paper states its bound :math:`\gamma = 0.0013` LU and its 0.1 deg angle noise, but neither its orbit, nor its
disturbance, nor a sampling interval.  This module holds the constants the paper gives, the choices this
reproduction makes where it gives none (each named), and :func:`paper_scenario`, the planar resonant orbit whose
scheduling parameters bound the LPV polytope.

Frame and units: the rotating frame of :mod:`cislunar.estimation.lpv`, non-dimensional (LU, TU); planar states
``[x, y, vx, vy]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cislunar.cr3bp.dynamics import CR3BP, EARTH_MOON, check_system
from cislunar.cr3bp.propagation import propagate
from cislunar.estimation.lpv import (
    CR3BPLPV,
    ParameterBox,
    ResonantOrbit,
    resonant_orbit,
)
from cislunar.utils import validation

__all__ = [
    "GAMMA",
    "POLE_RADIUS",
    "RESONANT_CANDIDATES",
    "SIGMA_DEG",
    "SIN3_THRESHOLD",
    "THETA1_SENSORS",
    "Fig1Scene",
    "Scenario",
    "fig1_scene",
    "paper_scenario",
]

#: The paper's bound on the position error, LU (about 500 km), §IV-B.
GAMMA = 0.0013
#: The paper's simulated angle noise, deg (Fig. 3).
SIGMA_DEG = 0.1
#: H-infinity bandwidth bound R, 1/TU (beyond the paper: makes Theorem 2's minimum attained; about 1 per 6 min).
POLE_RADIUS = 1000.0
#: The sensors the comparison rows offer: sin and cos of theta1 (the ones Eq. 24 uses and the l1 optimum keeps).
THETA1_SENSORS = (0, 1)
#: Below this :math:`|\sin\theta_3|` the observer takes rho from its estimate (paper, §IV-B).
SIN3_THRESHOLD = 0.04
#: Planar Earth-Moon resonant orbits tried by the sensitivity study: (p, q, perigee radius in LU).  Each is an
#: x-axis symmetric orbit that :func:`cislunar.estimation.lpv.resonant_orbit` corrects (5:3, 3:2 and 7:4 guesses
#: do not converge with the Keplerian start and are left out).
RESONANT_CANDIDATES = ((4, 1, 0.2), (3, 1, 0.2), (3, 1, 0.3), (5, 2, 0.35), (2, 1, 0.2), (2, 1, 0.3),
                       (2, 1, 0.4), (2, 1, 0.5))


@dataclass(frozen=True)
class Scenario:
    """The documented set-up of this reproduction: model, resonant orbit, its samples and the parameter box.

    Attributes
    ----------
    model : CR3BPLPV
    orbit : ResonantOrbit
    t : ndarray (n,)
        Sample times over one period, TU.
    states : ndarray (n, 4)
        Planar states along the orbit (LU, LU/TU).
    rho : ndarray (n, 6)
        Scheduling parameters along the orbit.
    box : ParameterBox
        Bounds of ``rho`` along the orbit (the polytope whose vertices carry the LMIs).
    """

    model: CR3BPLPV
    orbit: ResonantOrbit
    t: np.ndarray
    states: np.ndarray
    rho: np.ndarray
    box: ParameterBox

    @property
    def r13_range(self) -> tuple:
        """Smallest and largest Earth distance on the orbit, LU."""
        r13 = 1.0 / self.rho[:, 2]
        return float(r13.min()), float(r13.max())


def paper_scenario(system: CR3BP = EARTH_MOON, *, p: int = 2, q: int = 1, perigee_radius: float = 0.3,
                   n_samples: int = 2000, margin: float = 0.0) -> Scenario:
    """Resonant orbit (default the planar 2:1, perigee 0.3 LU) and the scheduling-parameter box over one period.

    ``n_samples`` points over one period bound :math:`\\rho`; ``margin`` widens the box by that fraction of
    each range (0 by default: the samples are dense enough that the extrema are resolved to ~1e-5).
    """
    model = CR3BPLPV(check_system(system, "system"))
    n_samples = validation.integer(n_samples, "n_samples", minimum=2)
    margin = validation.positive(margin, "margin", allow_zero=True)
    orbit = resonant_orbit(system, p, q, perigee_radius)
    t, x = orbit.sample(n_samples)
    s = model.planar(x)
    rho = model.rho(s)
    box = ParameterBox.from_samples(rho, margin=margin,
                                    source=f"planar {p}:{q} resonant orbit, x0 = {orbit.x0[0]:.6f} LU, "
                                           f"vy0 = {orbit.x0[4]:.6f} LU/TU, T = {orbit.period:.6f} TU")
    return Scenario(model, orbit, t, s, rho, box)


@dataclass(frozen=True)
class Fig1Scene:
    """The paper's Fig. 1 set-up: surveillance platforms spread along a planar resonant orbit tracking an RSO.

    Attributes
    ----------
    orbit : ndarray (n, 4)
        The platforms' orbit over one period (LU, LU/TU).
    platforms : ndarray (k, 4)
        Platform states at the epoch, equally spaced in time along the orbit.
    rso_orbit : ndarray (n, 4)
        The RSO's orbit over one of its periods.
    rso : ndarray (4,)
        The RSO's state at the epoch.
    labels : tuple of str
        ``(platform orbit, RSO orbit)`` labels.
    """

    orbit: np.ndarray
    platforms: np.ndarray
    rso_orbit: np.ndarray
    rso: np.ndarray
    labels: tuple


def fig1_scene(scenario: Scenario, n_platforms: int = 6, *, rso: tuple = (3, 1, 0.3), rso_phase: float = 0.3,
               n_samples: int = 400) -> Fig1Scene:
    """``n_platforms`` platforms equally spaced in time on ``scenario``'s orbit, and an RSO on the ``rso`` = (p, q,
    perigee radius) resonant orbit at ``rso_phase`` (fraction of its period) of its own orbit; both drawn over one
    period with ``n_samples`` points (the paper's Fig. 1 states no orbit: an illustration of the concept).

    ``rso`` holds the arguments of :func:`cislunar.estimation.lpv.resonant_orbit`: integers ``p > q >= 1`` (3.0 is
    accepted, 3.5 is refused, not truncated) and the perigee radius in LU, in [0.05, 0.9] and below the resonance's
    2a.  Any other value raises ``ValueError``/``TypeError`` naming ``rso``.
    """
    scenario = validation.instance(scenario, "scenario", Scenario)
    k = validation.integer(n_platforms, "n_platforms", minimum=1)
    phase = validation.in_range(rso_phase, "rso_phase", 0.0, 1.0)
    n = validation.integer(n_samples, "n_samples", minimum=10)
    if not isinstance(rso, (tuple, list, np.ndarray)) or (isinstance(rso, np.ndarray) and rso.ndim != 1):
        raise validation.ArgumentTypeError(f"rso must be a (p, q, perigee radius in LU) tuple; got "
                                           f"{type(rso).__name__} {rso!r:.60}")
    if len(rso) != 3:
        raise ValueError(f"rso must hold 3 items (p, q, perigee radius in LU); got {len(rso)}: {rso!r:.60}")
    p_q_rp = (validation.integer(rso[0], "rso[0] (p)"), validation.integer(rso[1], "rso[1] (q)"),
              validation.real(rso[2], "rso[2] (perigee radius, LU)"))
    m, o = scenario.model, scenario.orbit
    try:  # the resonance's own rules (p > q >= 1, perigee radius range), named as the caller's rso
        ro = resonant_orbit(m.system, *p_q_rp)
    except ValueError as exc:
        raise ValueError(f"rso = {rso!r:.60} is not a resonant orbit: {exc}") from None
    _, x = o.sample(n)
    tp = np.arange(k) * o.period / k
    platforms = m.planar(propagate(m.system, o.x0, np.r_[tp, o.period]).x[:k]) if k > 1 else m.planar(o.x0[None])
    _, xr = ro.sample(n)
    r_at = m.planar(propagate(m.system, ro.x0, [0.0, phase * ro.period + 1e-9]).x[-1])
    return Fig1Scene(m.planar(x), platforms, m.planar(xr), r_at,
                     (f"platform orbit ({o.p}:{o.q} resonant)", f"RSO orbit ({ro.p}:{ro.q} resonant)"))

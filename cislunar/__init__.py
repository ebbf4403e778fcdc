"""cislunar: a literate reproduction of four cislunar navigation and tracking papers.

Modules
-------
dynamics      CR3BP constants, units, vector field, Jacobian, Jacobi constant, libration points
propagation   heyoka.py propagation of states, STMs and second-order STTs; events; scipy cross-check path
orbits        symmetric periodic orbits: shooting, continuation, monodromy, stability; reference orbits
reference     reference-orbit tables transcribed from the papers (``data/``), each row verified
sites         observer sites: L2, DRO, lunar-surface stations; horizon and occultation geometry
measurements  relative position, range / range-rate, azimuth / elevation (+ rates), Jacobians, noise models
covariance    SPD helpers, process-noise discretisation, EKF covariance (CRLB) recursion, augmented states
information   mutual information of an observation window (dense Eq. 18 and O(N) chain rule) and its gradient
discretization  Sundman-spaced nodes and first-order-hold discretisation for SCvx
scvx          successive convexification (SCvx* augmented Lagrangian, quadratic MI model, first-order hold)
wolf_jones    Wolf & Jones test cases 1 and 2: scenarios, information models, keep-out, CRLB and Pareto helpers
srif          square-root information filter and smoother (Householder)
ocbe          optimal-control-based estimator: state/costate transition, Eq. 17 process noise, SRI filter/smoother
adaptive_ocbe  adaptive OCBE tuning: the OCBE metric and its law, 99 % limit, three-epoch rule, covariance reset
tracking      optical tracking scenarios (truth with impulses, measurements, hand-off, NEES consistency trials)
detection     station-keeping policies, batched OCBE Monte Carlo, control-integral hypothesis test
torus         2-D quasi-periodic invariant tori by the invariant-circle (GMOS) method; the 215-km QPO member
ssat          spacecraft-to-spacecraft absolute tracking: two-vehicle states, SSAT covariance analysis, MMD guidance
station_keeping  informed station keeping on a QPO: two-burn transfers, surfaces, informed maneuver, filter trials
montecarlo    Monte Carlo trials and sweeps through any concurrent.futures-style executor
lpv           LPV form of the planar CR3BP and H2 / H-infinity sensing-precision LMIs
observers     LPV observer and EKF simulations on the nonlinear CR3BP
plotting      packaged matplotlib style, ``save_figure``, rotating-frame plot helpers
report        paper-vs-reproduction tables gathered into ``build/report.md``
progress      one progress bar for long loops (widget, plain text when headless, or off)
notebooks     command-line runner executing ``notebooks/NN_*.py`` with papermill
book          static HTML book from the executed notebooks (Sphinx + myst-nb, offline)
"""

from .dynamics import CR3BP, EARTH_MOON

__all__ = ["CR3BP", "EARTH_MOON"]
__version__ = "0.1.0"

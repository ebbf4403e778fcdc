"""Claims of notebook 08, QPO-informed station keeping (Greaves & Scheeres AMOS 2023, Secs. 4-5, Eq. 25,
Figs. 2-5).

Declarations only: each closing-table row of the chapter, its criterion fixed before comparing.  Valley rows: the
median over the arrival slices of the percentile of u* (percent of a slice's maneuvers with a smaller sqrt(J_rho) at
t_f; 0 = best), at most 25 (the best quartile).  Fuel rows: percent of slices where u* uses at most the slice's
median fuel, at least 90.  Improvement rows: sqrt(J_rho) of u* over the no-maneuver value, at most 0.5.
"""

from __future__ import annotations

from cislunar.publish.claims import AtLeast, AtMost, Claim, Holds, Within

CLAIMS = {
    "mean_range": Claim(
        "QPO member: mean agent-target range", "215 km", Within(215.0, 0.01), kind="derived", source="Sec. 4"),
    "ring_size": Claim(
        "QPO ring size (RMS about centre)", None, kind="not in paper", reason="the paper gives no torus parameters"),
    "rotation_number": Claim(
        "QPO rotation number (rad per NRHO period)", None, kind="not in paper",
        reason="stroboscopic time = NRHO period (same base frequency)"),
    "range_extremes": Claim(
        "agent-target range min / max on the torus", None, kind="not in paper",
        reason="min/max over all ring angles and one period"),
    "fig2": Claim(
        "Fig. 2: torus surface about the NRHO near apoapsis", "figure", kind="derived", source="Fig. 2"),
    "transfer_miss": Claim(
        "two-burn transfer reaches the torus point", None, AtMost(1e-9), kind="beyond paper"),
    "fig3_burns": Claim(
        "Fig. 3: first / second burn ranges over the surface", "figure (values not printed)", kind="not in paper",
        reason="depends on the unstated burn epoch and arrival window (section 3)", source="Fig. 3"),
    "valley_angle": Claim(
        "Fig. 4: u* lies in the valley of sqrt(J_rho) (median percentile within slices)", "in the valley",
        AtMost(25.0), source="Sec. 5, Fig. 4",
        reason="Eq. 25 read as the angle between u_y and the first burn (the printed denominator makes every angle 0 "
               "or pi) picks maneuvers next to the agent's own phase, the smallest burns, far from the valley (a "
               "random pick sits at the 50th percentile on average)"),
    "valley_projection": Claim(
        "Fig. 4: u* in the valley, Eq. 25 read as the projection of the burn on u_y", "in the valley",
        AtMost(25.0), source="Sec. 5, Fig. 4",
        tuned="this reading of Eq. 25 was chosen because it matches the paper's Fig. 4",
        reason="the projection reading's u* is outside the best quartile of its slices"),
    "fuel_angle": Claim(
        "Fig. 5: guidance avoids the largest fuel costs (angle reading)", "avoids the peak", AtLeast(90.0),
        source="Sec. 5, Fig. 5",
        reason="u* uses more than its slice's median fuel in more than 10 % of the slices"),
    "fuel_projection": Claim(
        "Fig. 5: guidance avoids the largest fuel costs (projection reading)", "avoids the peak", AtLeast(90.0),
        source="Sec. 5, Fig. 5",
        reason="u* uses at most its slice's median fuel in fewer than 90 % of the slices: the projection reading "
               "buys its place in the valley with a large burn along u_y"),
    "second_burn_peak": Claim(
        "second burn's effect on sqrt(J_rho) of u* ('small local peak')", "raises one point",
        Holds("the second burn raises sqrt(J_rho) of u* (ratio both burns / first burn only > 1) in some slice"),
        source="Sec. 5",
        reason="rerun of u* without its second burn: when tracking starts at the first burn, the second burn (a kink "
               "in a tracked arc) is where the range information comes from, so it lowers sqrt(J_rho) everywhere"),
    "improves_angle": Claim(
        "u* improves range knowledge vs no maneuver (covariance analysis, angle reading)", "'significantly improves'",
        AtMost(0.5), source="Sec. 6 (conclusions)",
        reason="sqrt(J_rho) of u* is not below half the no-maneuver value at every ring-angle grid"),
    "improves_projection": Claim(
        "u* improves range knowledge vs no maneuver (projection reading)", "'significantly improves'", AtMost(0.5),
        source="Sec. 6 (conclusions)", reason="sqrt(J_rho) of u* is not below half the no-maneuver value"),
    "filter_nees": Claim(
        "full filter: NEES at t_f, informed (angle / projection), execution errors", "future work",
        kind="beyond paper", source="Sec. 6 (future work)"),
    "filter_no_maneuver": Claim(
        "full filter: no maneuver (NEES at t_f; RMS range error vs filter 1-sigma)", "future work",
        kind="beyond paper"),
    "filter_small_errors": Claim(
        "full filter: RMS range error at t_f with 10x smaller execution errors, informed (angle / projection) / "
        "uninformed", "future work", kind="beyond paper"),
    "filter_rms": Claim(
        "full filter: RMS range error at t_f, informed (angle / projection) vs uninformed (exec. errors) vs none",
        "future work", kind="beyond paper"),
}

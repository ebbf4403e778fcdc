"""Claims of Wolf & Jones test case 2 (Tables 4-5, Figs. 6-10), judged in notebook 06.

Declarations only.  Tolerances fixed before comparing: the window ends to the paper's "roughly" (1 day);
"out-of-plane motion" means more than 100 km out of plane; "weakly observable at alpha_h = 0" a terminal observer
RMS at least five times that of every alpha_h > 0; "correlates well" a Spearman rank correlation of MI against
terminal RMS of at most -0.8; the observer "on average" better than the targets a window-mean RMS at least 10 %
lower than the targets' mean; the front is monotone if no plan has both more impulse and a higher RMS than another;
two plans are mirror images within 1 km and 1e-6 relative cost.  The Fig. 9 and Fig. 10 rows rest on the
process-noise reading chosen by looking at the paper's figures (tuned: the literal reading contradicts them); the
growth of impulse and MI with alpha_h is implied by optimality (derived).
"""

from __future__ import annotations

from cislunar.papers.wolf_jones.reference import CLOSURE_TOL
from cislunar.publish.claims import AtLeast, AtMost, Claim, Equals, Holds

_Q_TUNED = ("the process-noise reading (q = 1e-11 LU^2/TU^3) was chosen as one that keeps test case 1's CRLB "
            "bounded, the paper's own claim")
_SLIP_TUNED = ("the x0-held reading of the Table 2/4 slip, which sets P, was first chosen with these day counts in "
               "view")
_Q_READING_TUNED = ("holds under the adopted process-noise reading q = 1e-11 LU^2/TU^3, chosen among the readings of "
                    "Table 5's '1e-11 km/s^3' by looking at the paper's figures (test case 1's bounded CRLB, Fig. 4); "
                    "under the literal 1e-11 km^2/s^3 it fails: the alpha_h = 0 plan ends no worse than the "
                    "information plans and MI and CRLB rank-correlate positively (the readings row prints the value); "
                    "section 9 compares the readings")
#: Why "impulse and MI grow with alpha_h" is no evidence for the paper: for global optima x_1, x_2 of the weighted
#: sum J = (1 - a) impulse - a MI at a_1 < a_2 over the same feasible set, the two optimality inequalities, each
#: divided by 1 - a and added, give MI_2 >= MI_1 and then impulse_2 >= impulse_1.  The row checks that the sweep's
#: plans behave like global optima, not the paper.
_OPTIMALITY_FAILS = ("the plans are not all global optima: for global optima of the weighted sum (1 - alpha_h) "
                     "impulse - alpha_h MI, impulse and MI cannot decrease as alpha_h grows")
_NO_KEEP_OUT = ("at a weight run without a keep-out even our modified solver does not converge (convex subproblem "
                "fails or the iteration limit is hit)")

CLAIMS = {
    "observer_t0_periodic": Claim(
        "Table 4 observer x_S(t0) is a periodic DRO", "implied (DRO family)", AtMost(CLOSURE_TOL), source="Table 4",
        reason="the printed vy0 is not periodic (closure after one period, non-dimensional)"),
    "other_rows_periodic": Claim(
        "Table 4 other rows periodic", "implied", AtMost(CLOSURE_TOL), source="Table 4",
        reason="a row does not close"),
    "table5_title": Claim(
        "Table 5 title", '"Scenario Parameters for Test Case #1"', Equals("test case 1"), source="Table 5",
        reason="title slip: range/range-rate noise and three targets belong to test case 2"),
    "a_max": Claim("Table 5 a_max", '"1x5^-7" km/s^2', kind="derived", source="Table 5"),
    "process_noise": Claim(
        "Table 3/5 process noise Q", '1e-11 "km/s^3"',
        Holds("test case 1's ballistic CRLB is bounded after the transient under the adopted reading"),
        tuned=_Q_TUNED, source="Tables 3 and 5", reason="the adopted reading does not keep the CRLB bounded"),
    "window": Claim(
        "Observation window", "roughly 17-32 days", AtMost(1.0), tuned=_SLIP_TUNED, source="Test Case #2 text",
        reason="a window end misses the text's day count by more than 1 day (largest miss, days)"),
    # widened 2026-11-26 (a referee): the paper implies convergence at every weight; the row used to judge the Fig. 6
    # weight alone although the diagnosis of section 11 runs another weight without a keep-out
    "no_keep_out": Claim(
        "SCvx converges without a keep-out at every weight run so (our modified solver: the Fig. 6 weight and the "
        "diagnosed weight)", "implied (Figs. 7, 10)",
        Holds("every weight run without a keep-out converges"), source="Figs. 7, 10", reason=_NO_KEEP_OUT),
    "keep_out_converges": Claim(
        "modified SCvx with a 424 km keep-out converges for every alpha_h", "-",
        Holds("every alpha_h of the grid has a converged plan"), kind="beyond paper",
        reason="an alpha_h has no converged plan"),
    "reflight": Claim("Single-shooting re-flight of the converged controls", "not in paper", kind="beyond paper"),
    "out_of_plane": Claim(
        "Fig. 6: out-of-plane motion at alpha_h = 1e-2", "yes", AtLeast(100.0), source="Fig. 6",
        reason="the solution stays (nearly) planar (largest |z|, km)"),
    "departure": Claim(
        "Fig. 7: departure grows with alpha_h", "generally",
        Holds("Spearman(alpha_h, largest departure) above 0.8 on every node grid"), source="Fig. 7",
        reason="not robust across node grids"),
    "mirror_pair": Claim(
        "Fig. 7: the 5e-3 and 7e-3 solutions are near-mirror images across z = 0", "yes (Fig. 7)",
        Holds("one optimum lies closer to the mirror of the other than to the other itself"), source="Fig. 7",
        reason="the sweep's two optima lie closer to each other than to each other's mirror"),
    "mirror_optimum": Claim(
        "Fig. 7 z-mirror: the mirror of an optimum is an optimum", "postulated family of symmetric optima",
        Holds("the re-solved mirror has its cost within 1e-6 relative and lies within 1 km of the exact mirror"),
        kind="beyond paper", source="Fig. 7 discussion", reason="the mirror is not re-accepted as an optimum"),
    "seeds": Claim(
        "Fig. 7: +z and -z seeds at alpha_h = 5e-3 and 7e-3", "near-mirror solutions (Fig. 7)",
        Holds("the two seeds converge to mirror images within 1 km and 1e-6 relative cost"), kind="beyond paper",
        source="Fig. 7", reason="the seeds converge to different local optima"),
    "window_thrust": Claim(
        "Fig. 8: zero thrust in the window", "a_max = 0 in the window", AtMost(1e-12), kind="derived",
        source="Table 5; Fig. 8", reason="thrust inside the window (an imposed input)"),
    "a_z_used": Claim(
        "Fig. 8: out-of-plane thrust a_z used", "yes",
        Holds("max |a_z| > 1e-3 a_max in every plan with alpha_h > 0"), source="Fig. 8",
        reason="some plans stay planar"),
    "weakly_observable": Claim(
        "Fig. 9: alpha_h = 0 weakly observable (grey)", "yes",
        Holds("terminal observer RMS at alpha_h = 0 at least 5 times that of every alpha_h > 0"),
        tuned=_Q_READING_TUNED, source="Fig. 9", reason="the baseline is not much worse"),
    "observer_below_targets": Claim(
        "Fig. 9: observer RMS below the targets' on average", "yes", AtLeast(0.10), source="Fig. 9",
        reason="the observer's window-mean RMS is less than 10 % below the targets' mean (smallest relative gap)"),
    "mi_correlation": Claim(
        "Fig. 10: MI correlates with estimator performance", "'correlates well'", AtMost(-0.8),
        tuned=_Q_READING_TUNED, source="Fig. 10; abstract",
        reason="weak rank correlation (larger of the observer's and targets' Spearman coefficients)"),
    "front_grows": Claim(
        "Fig. 10: impulse and MI grow with alpha_h (implied by optimality)", "yes",
        Holds("impulse and MI non-decreasing over the grid, as for any set of global optima of the weighted sum"),
        kind="derived", source="Fig. 10",
        reason=_OPTIMALITY_FAILS),
    "front_monotone": Claim(
        "Fig. 10: front monotone in (impulse, RMS): more impulse, lower RMS", "a trade-off front",
        Holds("no plan has both more impulse and a higher observer terminal RMS than another"), source="Fig. 10",
        reason="a plan is worse on both axes than a cheaper one"),
    "values": Claim(
        "Impulse and terminal RMS values (Figs. 8-10)", "plotted, no numbers printed", kind="not in paper",
        reason="the figures carry no readable values in the text version"),
    "mesh": Claim("node grid (unstated N and sigma), at the Fig. 6 weight", "N, sigma not given", kind="beyond paper"),
    "budget": Claim("Improvement over the minimum-impulse baseline at a prescribed impulse (solved)", "substantial",
                    kind="beyond paper"),
    "cheap": Claim("Improvement over the minimum-impulse baseline", "substantial", kind="beyond paper"),
    "keep_out_radius": Claim("Keep-out radius (unstated input), swept at the Fig. 6 weight", "not in paper",
                             kind="beyond paper"),
    # issue 22, item 1 (global quality); tolerances fixed before the runs: two plans are one optimum when their
    # costs agree within 1e-6 (1 + |J|) and their node positions (or z-mirrors) within 100 km; a plan is
    # mesh-converged when impulse, MI and terminal RMS change by at most 5 % between the two finest grids
    "distinct_optima": Claim("distinct local optima per alpha_h (multi-start: ballistic, +/-z seeds, random, "
                             "neighbours, the sweeps)", "not discussed", kind="beyond paper"),
    "multi_start": Claim("multi-start against the sweeps' best plan", "-", kind="beyond paper"),
    "envelope": Claim("Fig. 10 front as the lower envelope over every optimum found", "one curve (Fig. 10)",
                      kind="beyond paper"),
    "mesh_study": Claim(
        "plans converged in the node grid at the headline weights (mesh study up to 60 nodes)", "N, sigma not given",
        Holds("impulse, MI and observer terminal RMS change by at most 5 % between the two finest grids at every "
              "headline weight"), kind="beyond paper",
        reason="at a headline weight the best plan found changes by more than the 5 % tolerance between the two "
               "finest grids (the plan moves with the grid, or the starts reach another local optimum on one of "
               "them: the note names the start of the finest grid's best plan)"),
    # AtMost(1e-6): the multi-start's own "same optimum" tolerance on the cost, 1e-6 (1 + |J|) (global_search)
    "mesh_back": Claim(
        "multi-start's generic starts find the best known plan of their grid (each weight's finest mesh-study plan "
        "moved back, re-solved)", "-", AtMost(1e-6), kind="beyond paper",
        reason="a plan from a finer grid, moved back onto the figures' grid, converges to a lower cost there: an "
               "optimum the generic starts did not find (adopted from then on, as one more start)"),
    "gradient": Claim(
        "MI gradient (reverse mode of Eq. 18) vs central differences, case 2 window", "Eqs. 44-52 (formula only)",
        AtMost(1e-5), kind="beyond paper", source="Eqs. 44-52", reason="gradient and value disagree"),
}

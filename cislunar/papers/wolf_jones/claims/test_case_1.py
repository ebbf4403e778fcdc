"""Claims of Wolf & Jones test case 1 (Tables 2-3, Figs. 1-5), judged in notebook 05.

Declarations only.  Tolerances fixed before comparing: a qualitative claim holds when the stated behaviour holds
for every alpha_h of the grid; day counts of the text within 1 day; a "bounded" CRLB means a window-end RMS no
larger than at the 2nd measurement; "correlates well" a Spearman rank correlation of at most -0.8.

"Impulse and MI grow with alpha_h" is implied by optimality: for global optima x_1, x_2 of J = (1 - a) impulse - a MI
at a_1 < a_2 over the same feasible set, the two optimality inequalities, each divided by 1 - a and added, give
MI_2 >= MI_1 and then impulse_2 >= impulse_1.  It is a derived row: it checks that the sweep's plans behave like
global optima, not the paper.
"""

from __future__ import annotations

from cislunar.papers.wolf_jones.reference import CLOSURE_TOL
from cislunar.publish.claims import AtMost, Claim, Equals, Holds

_Q_TUNED = ("the process-noise reading (q = 1e-11 LU^2/TU^3) was chosen as one that keeps this case's CRLB bounded, "
            "the very property claimed")
_SLIP_TUNED = "the x0-held reading of the Table 2 slip was first chosen with the text's day counts in view"

CLAIMS = {
    "observer_t0_periodic": Claim(
        "observer x_S(t0) (Table 2) is a DRO", "vy0 = 0.528996986", AtMost(CLOSURE_TOL),
        source="Table 2", reason="the printed vy0 is a slip (closure after one period, LU)"),
    "observer_tf_periodic": Claim(
        "Table 2 observer x_S(t_f) is a periodic DRO", "implied (DRO family)", AtMost(CLOSURE_TOL),
        source="Table 2", reason="the printed row does not close"),
    "target1_t0_periodic": Claim(
        "Table 2 target x_T(1)(t0) is a periodic DRO", "implied (DRO family)", AtMost(CLOSURE_TOL),
        source="Table 2", reason="the printed row does not close"),
    "slip_reading": Claim(
        "which number of x_S(t0) slipped (x0 or vy0)", "orbits called 'adjacent'; six other rows printed",
        Holds("the adopted reading's x0 and period lie inside the span of the other rows, the rejected one's not"),
        kind="derived", source="Tables 2 and 4; text", reason="adjacency does not single out one reading"),
    "window": Claim(
        "observation window", "[3P/4, 3P/2]; text: '12 and 23 days'", AtMost(1.0), tuned=_SLIP_TUNED,
        source="Test Case #1 text", reason="3P/2 misses the text's 23 d by more than the 1-day tolerance "
                                          "(largest miss of 12 d and 23 d, days)"),
    "fig3_alpha": Claim(
        "Fig. 3 alpha_h of the left panel", "text: 5e-2; Fig. 3 caption and Fig. 1: 5e-3", Equals(5e-2),
        source="Test Case #1 text, Fig. 3 caption, Fig. 1",
        reason="the text's 5e-2 is a slip: the caption of Fig. 3 itself and Fig. 1 give 5e-3"),
    "process_noise": Claim(
        "process noise Q (Table 3)", "1e-11 'km/s^3'",
        Holds("the CRLB stays bounded after the transient for every alpha_h under the adopted reading"),
        tuned=_Q_TUNED, source="Table 3", reason="the adopted reading does not keep the CRLB bounded"),
    "literal_q_bounded": Claim(
        "CRLB under the literal Q = 1e-11 km^2/s^3: bounded after the transient?", "bounded (Fig. 4)",
        Holds("window-end RMS at most the 2nd measurement's under 1e-11 km^2/s^3, for alpha_h = 0 and the largest"),
        tuned=_Q_TUNED, source="Fig. 4; Table 3", reason="the literal reading grows (rejected)"),
    "window_thrust": Claim(
        "zero thrust in the observation window", "a_max = 0 in the window", AtMost(1e-12), kind="derived",
        source="Table 3", reason="thrust inside the window (an imposed input)"),
    # Revised 2026-11-26g (a referee of notebook 03): this row judged the paper's implied convergence with our
    # strict stopping test, which asks for an inactive trust region that a linear MI model's step never has, so it
    # could not pass whatever the printed method does.  The paper's claim is judged once, in notebook 03, under the
    # practical rule fixed there before any run (its gamma sweep: the printed method stops at gamma = 1e2); this
    # row keeps the strict-test sweep as a record.
    "printed_scvx": Claim(
        "printed SCvx (L1 exact penalty, linear MI of Eq. 44) under our strict stopping test, alpha_h = 5e-3, gamma "
        "sweep (the paper's claim is judged in notebook 03 under the practical rule)", "implied (Figs. 2, 5)",
        kind="beyond paper", source="Eqs. 24-36, 43-44"),
    "printed_scvx_long": Claim("printed SCvx at gamma 1e3 with a larger iteration limit", "-", kind="beyond paper"),
    "modified_scvx": Claim(
        "modified SCvx converges for every alpha_h of the grid", "-",
        Holds("every run converges with defects <= 1e-9"), kind="beyond paper",
        reason="a run of the modified solver fails"),
    "departure": Claim(
        "larger alpha_h -> larger departure from the DRO (Fig. 2)", "yes",
        Holds("largest distance from the DRO non-decreasing over the grid"), source="Fig. 2",
        reason="the departure is not monotone"),
    "front_monotone": Claim(
        "impulse and MI grow with alpha_h (Fig. 5; implied by optimality)", "yes",
        Holds("impulse and MI both non-decreasing over the grid (1e-6 relative), as for any set of global optima of "
              "the weighted sum"), kind="derived", source="Fig. 5",
        reason="the front is not monotone: the plans are not all global optima (for global optima of the weighted "
               "sum (1 - alpha_h) impulse - alpha_h MI, impulse and MI cannot decrease as alpha_h grows)"),
    "transient": Claim(
        "CRLB transient at the window start (Fig. 4)", "yes",
        Holds("RMS grows from the 1st to the 2nd measurement for every alpha_h"), source="Fig. 4",
        reason="no transient"),
    "bounded": Claim(
        "CRLB bounded after the transient (Fig. 4)", "yes",
        Holds("window-end RMS at most the 2nd measurement's for every alpha_h"), tuned=_Q_TUNED, source="Fig. 4",
        reason="the CRLB grows after the transient"),
    "information_gain": Claim(
        "more information -> lower terminal RMS (Figs. 4-5)", "observer and target",
        Holds("observer and target terminal RMS lower at the largest alpha_h than at alpha_h = 0"),
        source="Figs. 4-5", reason="no gain"),
    "mi_correlation": Claim(
        "MI correlates with estimator performance", "'correlates well'", AtMost(-0.8), source="abstract; Fig. 5",
        reason="weak rank correlation (larger of the observer's and target's Spearman coefficients)"),
    "reflight": Claim("single-shooting re-flight of every plan", "-", kind="beyond paper"),
    "mesh": Claim("node grid (mesh check, alpha_h = 5e-3)", "N not given", kind="beyond paper"),
    "budget": Claim("baseline vs information plan at a prescribed impulse (solved)", "'substantial improvement'",
                    kind="beyond paper"),
    "pareto_values": Claim(
        "Pareto values (impulse, terminal RMS)", "plotted only (Fig. 5), no numbers", kind="not in paper",
        reason="the paper's axes are not quantitatively readable; N and sigma of the nodes are not given either"),
    "local_optima": Claim("upward vs downward sweep (local optima)", "not discussed", kind="beyond paper"),
    # issue 22, item 1 (global quality); tolerances fixed before the runs: two plans are one optimum when their
    # costs agree within 1e-6 (1 + |J|) and their node positions (or z-mirrors) within 100 km; a plan is
    # mesh-converged when impulse, MI and terminal RMS change by at most 5 % between the two finest grids
    "distinct_optima": Claim("distinct local optima per alpha_h (multi-start: ballistic, +/-z seeds, random, "
                             "neighbours, the sweeps)", "not discussed", kind="beyond paper"),
    "multi_start": Claim("multi-start against the sweeps' best plan", "-", kind="beyond paper"),
    "envelope": Claim("Fig. 5 front as the lower envelope over every optimum found", "one curve (Fig. 5)",
                      kind="beyond paper"),
    "mesh_study": Claim(
        "plans converged in the node grid at the headline weights (mesh study up to 60 nodes)", "N not given",
        Holds("impulse, MI and observer terminal RMS change by at most 5 % between the two finest grids at every "
              "headline weight"), kind="beyond paper",
        reason="the near-impulsive plans move with the grid by more than the 5 % tolerance"),
    # AtMost(1e-6): the multi-start's own "same optimum" tolerance on the cost, 1e-6 (1 + |J|) (global_search)
    "mesh_back": Claim(
        "multi-start's generic starts find the best known plan of their grid (each weight's finest mesh-study plan "
        "moved back, re-solved)", "-", AtMost(1e-6), kind="beyond paper",
        reason="a plan from a finer grid, moved back onto the figures' grid, converges to a lower cost there: an "
               "optimum the generic starts did not find (adopted from then on, as one more start)"),
}

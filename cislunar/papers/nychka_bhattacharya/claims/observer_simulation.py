"""Claims of notebook 12 (Nychka & Bhattacharya §IV-B, Fig. 3): the closing-table rows, declared before comparing.
Criteria fixed before the runs: "converges rapidly" = first below the LMI's guaranteed RMS within 5 % of a period,
"stays accurate" = RMS after that below the guarantee; the error comparison uses medians after 10 % of the run."""

from cislunar.publish.claims import AtLeast, Claim, Holds, Within, printed_tolerance

_CONVERGES = ("first below the guaranteed RMS within 5 % of a period and the RMS after it (from 2 % of a period "
              "later) below the guarantee")

_TUNED_233 = ("sampling interval chosen so that H2 allows the paper's 0.1 deg per sample (the paper states none), on "
              "the 2:1 orbit (one of eight tried)")

CLAIMS = {
    "h2_gain": Claim(
        "h2 gain: solve status and verification", None,
        Holds("solve optimal, A + LC Hurwitz and norm < gamma at every checked point"), kind="beyond paper",
        reason="verification failed"),
    "hinf_gain": Claim(
        "hinf gain: solve status and verification", None,
        Holds("solve optimal, A + LC Hurwitz and norm < gamma at every checked point"), kind="beyond paper",
        reason="verification failed"),
    "ordering_dt": Claim(
        "ordering of allowances at the simulated dt", "H2 0.1 > Hinf 0.08 deg", Within(0.1, printed_tolerance("0.1")),
        source="§IV-B", reason="the H2 per-sample allowance at this dt is not the paper's 0.1 deg"),
    "h2_converges": Claim(
        "H2: converges rapidly and stays accurate", "yes (Fig. 3)", Holds(_CONVERGES), source="Fig. 3, §IV-B"),
    "hinf_converges": Claim(
        "Hinf: converges rapidly and stays accurate", "yes (Fig. 3)", Holds(_CONVERGES), source="Fig. 3, §IV-B"),
    "hinf_larger": Claim(
        "Hinf error larger than H2", "yes (Fig. 3c)",
        Holds("median position error after 10 % of the run larger for Hinf, at both dt"), source="Fig. 3c",
        tuned="shown on the 2:1 orbit (one of the eight tried in notebook 11) at two sampling intervals (the "
              "notebook's and the one where H2 allows 0.1 deg per sample), not under every reading",
        reason="H2 error not smaller at one of the two dt"),
    "rho_from_estimate": Claim("rho from estimate where |sin th3| < 0.04", "used", kind="derived"),
    "no_range": Claim(
        "observers function without range sensors", "yes (Fig. 3)",
        Holds("no range channel in the gains and each observer's RMS error after convergence within its own LMI "
              "guarantee, at both sampling intervals"), source="Fig. 3",
        reason="range channels used, or an observer's error above its own guarantee"),
    "fig3_233": Claim(
        "Fig. 3 accuracy at the interval where H2 allows 0.1 deg per sample", "accurate (Fig. 3)",
        Holds("both observers, rho triangulated from the noisy angles, from the large initial error: RMS error after "
              "10 % of the run within the LMI's guarantee"), source="Fig. 3, §IV-B", tuned=_TUNED_233,
        reason="the nominal guarantee assumes exact rho; the triangulated rho leaves the polytope and adds "
               "gravity and sensor errors the LMIs do not see"),
    "small_e0": Claim(
        "Fig. 3 accuracy from a small initial error (1 % of the large one)", "accurate (Fig. 3)",
        Holds("both observers, triangulated rho, from the small start: RMS error after 10 % of the run within the "
              "LMI's guarantee (the transient cannot be blamed)"), source="Fig. 3, §IV-B", tuned=_TUNED_233,
        reason="above the guarantee from the small start too: the scheduling error, not the transient"),
    "fig3_233_exact": Claim(
        "the same with rho from the truth (what the LMIs certify)", None,
        Holds("both observers within the nominal guarantee from both initial errors"), kind="beyond paper",
        reason="above the guarantee even with exact rho"),
    "robust": Claim(
        "robust LMIs (scheduling error as input, widened polytope): guarantee holds", None,
        Holds("both robust observers, triangulated rho, RMS error after 10 % of the run within sqrt(3) gamma* from "
              "both initial errors, and each robust gain verified on the widened polytope"), kind="beyond paper",
        reason="a robust observer above its guarantee or a gain not verified"),
    # Why the nominal and robust Hinf runs print the same RMS from both starts (found after the 233-min run, so a
    # diagnosis, beyond the paper; the 0.9 correlation was fixed before measuring it).
    "hinf_follows_fix": Claim(
        "Hinf at 233 min: error at each sample = the angle-only fix error of the sample before", None,
        AtLeast(0.9), kind="beyond paper", reason="the Hinf error does not follow the previous angle-only fix"),
    "ekf": Claim("EKF on same angles", None, kind="beyond paper"),
    "dt": Claim("measurement interval", "not stated", kind="not in paper",
                reason="choice of this reproduction; continuous sensor, noise held over each interval"),
}

"""Claims of the keep-out diagnosis and its remedy (test case 2 without a keep-out; notebook 06, section 11).

Declarations only.  The remedies' range scale rho_c = 141 km (the prior 1-sigma relative-position uncertainty
sqrt(2) * 100 km, below which the line of sight that carries the range-rate information is unknown) was fixed before
any run with it.  The diagnosis criteria (a failure at a reference closer than 10 km to a target, with an MI gradient
at least 100 times its value on the ballistic guess) were fixed after a first diagnosed run on 30 nodes (failure at
0.6 km, gradient 2000 times the ballistic one); any threshold between 1 and 500 km and between 10x and 1000x gives
the same verdicts there.  None of these rows is a paper number: the paper uses no keep-out and reports none.
"""

from __future__ import annotations

from cislunar.publish.claims import Claim, Holds

#: Range scale of the remedy's noise model sigma(rho) = sigma sqrt(1 + (rho_c / rho)^2), km (module docstring).
RANGE_SCALE_KM = 141.0
#: A failure counts as a close-pass failure when its last reference is closer than this to a target, km.
CLOSE_PASS_KM = 10.0
#: ... and the MI gradient there is at least this many times its value on the ballistic guess.
GRADIENT_GROWTH = 100.0

CLAIMS = {
    "free_failure": Claim(
        "test case 2 without a keep-out: what the convex subproblem hits", "-",
        Holds(f"a solver failure (not an infeasible constraint: the reference is feasible in every subproblem) at a "
              f"reference closer than {CLOSE_PASS_KM:g} km to a target, with an MI gradient at least "
              f"{GRADIENT_GROWTH:g} times the ballistic one"),
        kind="beyond paper",
        reason="the run without a keep-out did not fail that way (it converged, or failed elsewhere)"),
    "remedy_converges": Claim(
        f"test case 2 without a keep-out, range-dependent noise sigma sqrt(1 + ({RANGE_SCALE_KM:g} km / rho)^2)",
        "no keep-out in the paper", Holds("every weight solved converges (strict stop) with no keep-out"),
        kind="beyond paper", reason="a weight fails with the range-dependent noise too"),
    "remedy_plans": Claim(
        "plans with the range-dependent noise against the keep-out plans", "-", kind="beyond paper"),
    # the narrower remedy (same rho_c, declared with the first): only the range-rate row's 1/rho regularised
    "jacobian_remedy_converges": Claim(
        f"test case 2 without a keep-out, regularised range-rate Jacobian (1/rho -> 1/sqrt(rho^2 + "
        f"{RANGE_SCALE_KM:g}^2 km^2)), noise as in the paper", "no keep-out in the paper",
        Holds("every weight solved converges (strict stop) with no keep-out"), kind="beyond paper",
        reason="a weight does not converge with the regularised range-rate Jacobian (outcome in the row); it "
               "bounds the reward but not the MI gradient, which still grows like 1/rho near a target (the line "
               "of sight turns like 1/rho), so regularising that row alone is not enough to bound it"),
}

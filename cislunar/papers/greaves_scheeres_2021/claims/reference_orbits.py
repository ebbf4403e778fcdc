"""Claims of Greaves & Scheeres 2021 about its reference orbits and observer sites ("Dynamics", Table 1, Fig. 2;
"Measurements", Fig. 3), judged in notebook 01.

Declarations only.  The paper's Table 1 is missing from its text, so the NRHO rows are derived (the period imposed,
the stable member selected by its stability index) or compared with public values, not with the paper.  The
observer statements have no numbers in the paper: the criteria for "limited, infrequent and short" were written
after a first one-year count had been seen (tuned).
"""

from __future__ import annotations

from cislunar.cr3bp.dynamics import SYNODIC_MONTH_DAYS
from cislunar.publish.claims import Between, Claim, Equals, Holds, Within

_NO_TABLE1 = "not stated (Table 1 missing; 'approximate 9:2')"
#: Period of the 9:2 NRHO, days: two synodic months over nine revolutions (the resonance defines it).
T_9_2_DAYS = 2 / 9 * SYNODIC_MONTH_DAYS
_OUTAGES_TUNED = ("the paper gives no numbers; criteria written down after a first one-year count had been seen, "
                  "so not blind")
_DRO_TEST = "occulted < 5 % of time; mean interval > target period; longest < 6 h"

CLAIMS = {
    "nrho_period": Claim(
        "9:2 NRHO period [d]", _NO_TABLE1, Within(T_9_2_DAYS, 1e-8, relative=True), kind="derived",
        source="Dynamics ('approximate 9:2 resonance orbit')", reason="period constraint not met"),
    "nrho_perilune": Claim(
        "9:2 NRHO perilune radius [km]", _NO_TABLE1, Between(3200.0, 3300.0), kind="not in paper",
        reason="the paper prints no radius (its Table 1 is missing): compared with the public value instead"),
    "nrho_apolune": Claim(
        "9:2 NRHO apolune radius [km]", _NO_TABLE1, Within(71000.0, 1000.0), kind="not in paper",
        reason="the paper prints no radius (its Table 1 is missing): compared with the public value instead"),
    "nrho_state": Claim("9:2 NRHO apolune state [x0, z0, vy0]", _NO_TABLE1, kind="derived"),
    "nrho_stability": Claim(
        "9:2 NRHO stability index", "Table 1 missing", kind="not in paper",
        reason="Table 1 absent from the text; computed here"),
    "stable_stability": Claim(
        "stable NRHO stability index", "Table 1 missing", Within(1.0, 1e-3), kind="derived",
        reason="root finding failed"),
    "stable_perilune_period": Claim(
        "stable NRHO perilune radius [km] / period [d]", "Table 1 missing", kind="not in paper",
        reason="Table 1 absent; any member of the stable band has index 1, we take its boundary"),
    "outer_band": Claim(
        "outer stable band of the L2 halo family: perilune radius [km]", "not discussed", kind="beyond paper"),
    "outer_member": Claim(
        "stable NRHO, outer band: perilune [km] / period [d] / stability index", "Table 1 missing",
        kind="not in paper", reason="most stable member of the outer band (orbits.stable_nrho_outer); notebooks 09, "
                                    "09b and 10 carry both candidates"),
    "stm": Claim("STM vs central differences (9:2 period)", "-", kind="beyond paper"),
    "stt": Claim("STT vs central differences of the STM", "-", kind="beyond paper"),
    "l2_line_of_sight": Claim(
        "L2 observer line of sight to the 9:2 NRHO", "never interrupted", Equals(0), source="Measurements",
        reason="occultations found (count of outages)"),
    **{f"dro_outages_{key}": Claim(
        f"DRO observer outages ({name} NRHO)", "limited, infrequent and short", Holds(_DRO_TEST),
        tuned=_OUTAGES_TUNED, source="Measurements")
       for key, name in (("9_2", "9:2"), ("inner", "stable (inner)"), ("outer", "stable (outer)"))},
    "three_stations": Claim(
        "surface stations needed for the full 9:2 orbit", 3,
        Holds("no pair of grid sites covers 100 % of the samples while the default three do"),
        source="Measurements", reason="coverage incomplete or a grid pair suffices"),
}

"""Claims of Wolf & Jones about their reference orbits (Tables 2 and 4, the units of their "Dynamics" section and
the day counts of the test cases' windows), judged in notebook 01; measured by
:mod:`cislunar.papers.wolf_jones.reference_tables`.

Declarations only.  Every printed DRO state should close after one period within ``CLOSURE_TOL`` (1e-7 LU; rows
printed to nine digits close to about 1e-8); the window ends of the text within 1 day.
"""

from __future__ import annotations

from cislunar.papers.wolf_jones.reference import CLOSURE_TOL
from cislunar.papers.wolf_jones.reference_tables import TABLE_ROWS, WINDOW_TOL_DAYS, row_label
from cislunar.publish.claims import AtMost, Claim, Holds

CLAIMS = {
    "mu": Claim(
        "Earth-Moon mass ratio mu", "not stated",
        Holds("the six periodic rows close within CLOSURE_TOL at the adopted mu and fail for every trial "
              "|d mu| >= 0.9e-9"), kind="derived", reason="the printed rows do not pin mu to 1e-9"),
    "length_unit": Claim("length unit [km]", "not stated", kind="not in paper",
                         reason="our choice: mean Earth-Moon distance"),
    "time_unit_s": Claim("time unit [s]", "not stated", kind="not in paper",
                         reason="our choice: sqrt(L^3 / G(M_E + M_M)); W&J define it only in words (row below)"),
    **{f"closure_table{t}_{label}": Claim(
        f"W&J {row_label(t, label)}: closure of printed state", "periodic DRO", AtMost(CLOSURE_TOL),
        source=f"Table {t}", reason="printed vy0 is not periodic")
       for t, label in TABLE_ROWS},
    "window_case1": Claim(
        "W&J test case 1 observation window [d]", "12 to 23", AtMost(WINDOW_TOL_DAYS), source="Test Case #1 text",
        reason="the window end misses the text's day count by more than the 1-day tolerance (largest miss, days)"),
    "time_unit_reading": Claim(
        "W&J time unit", "P_synodic / 2 pi",
        Holds("the standard time unit fits the windows' day counts (12-23 d, 17-32 d) better than the literal "
              "reading P_synodic / 2 pi"), kind="derived", source="Dynamics",
        reason="the literal reading fits better"),
}

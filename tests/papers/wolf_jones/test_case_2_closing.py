"""The closing measurements of notebook 06 that combine several runs (cislunar.papers.wolf_jones.case_2_closing)."""

from __future__ import annotations

import dataclasses
import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from cislunar.papers.wolf_jones import case_2_closing
from cislunar.papers.wolf_jones import keep_out_diagnosis as kod
from cislunar.papers.wolf_jones.claims.test_case_2 import CLAIMS


def _plugin():
    """The valid baseline of the reliability plugin (small test-case-2 studies on 6 nodes, built once per process)."""
    folder = Path(__file__).resolve().parents[2] / "reliability"
    if str(folder) not in sys.path:  # the plugin imports its helper module from its own folder
        sys.path.insert(0, str(folder))
    path = folder / "reliability_specs_wolf_jones_studies.py"
    spec = importlib.util.spec_from_file_location("_wj_studies_plugin", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def baseline():
    p = _plugin()
    return dict(case=p.case2_graded(), row6=p.row6(), n_nodes=6, sigma=1.0, gc=p.gradient2(), ms=p.mirror2(),
                ko=p.keep_out_study(), nr=p.readings(), fr=p.front2(), departures=p.departures2(), obs_mean={},
                tgt_mean={}, common={}, budget_row=None, extra_mps=2.0, rtol=0.02)


def _diagnosis(outcome):
    e = np.array([])
    return kod.FreeRunDiagnosis(outcome, "", 3, e, e, e, e, np.nan, [])


def test_no_keep_out_row_needs_every_weight_run_without_a_keep_out_to_converge(baseline):
    """The paper implies convergence at every weight: one diagnosed weight that fails makes the row differ, whatever
    the Fig. 6 weight's run did; a converged diagnosed weight changes nothing; the outcome is shown whole."""
    a6 = baseline["row6"].alpha
    plain = case_2_closing.measurements(**baseline)["no_keep_out"]
    fail = "convex subproblem failed at iteration 7: Solver 'CLARABEL' failed. Try another solver, or solve with " \
           "verbose=True for more information."
    with_fail = case_2_closing.measurements(**baseline, diagnosed={2e-2: _diagnosis(fail)})["no_keep_out"]
    with_ok = case_2_closing.measurements(**baseline, diagnosed={2e-2: _diagnosis("converged (9 iterations)")})[
        "no_keep_out"]
    same_weight = case_2_closing.measurements(**baseline, diagnosed={a6: _diagnosis(fail)})["no_keep_out"]
    assert with_fail.value is False
    assert with_ok.value == plain.value and same_weight.value == plain.value  # the Fig. 6 weight is judged once
    assert "alpha_h = 0.02: convex subproblem failed at iteration 7: Solver 'CLARABEL' failed." in with_fail.shown
    assert "Try another solver" not in with_fail.shown
    assert CLAIMS["no_keep_out"].judge(with_fail.value, shown=with_fail.shown).status == "differs"
    with pytest.raises(TypeError, match=r"diagnosed\[0.02\]"):
        case_2_closing.measurements(**baseline, diagnosed={2e-2: "failed"})
    assert dataclasses.is_dataclass(with_fail)

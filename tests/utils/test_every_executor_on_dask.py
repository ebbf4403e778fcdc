"""Every public function of the package that takes an ``executor`` runs on a Dask cluster, bit-identical to serial.

Issue 20: ``executor`` may be a ``concurrent.futures`` pool or a ``distributed.Client``
(:func:`cislunar.utils.executors.open_executor` gives one when a notebook's ``SCHEDULER`` is set).  The functions
are found by walking the package (every public function, and public method of a public class, with a parameter
named ``executor``); each runs once serially and once through one module-scoped ``LocalCluster`` (two worker
processes, one thread each, so arguments, tasks and results cross a pickle boundary), and the two results must be
equal bit for bit (arrays with ``numpy.array_equal``, NaN equal to NaN; wall-clock fields excluded).

The smallest valid call of each function is the one its owners maintain for the malformed-argument sweep
(``tests/reliability/reliability_specs_*.py``, loaded the same way ``tests/reliability/test_reliability.py`` loads
them), with a few arguments overridden here (:data:`OVERRIDES`); functions without such a spec have their call in
:data:`CALLS`.  A function with neither fails :func:`test_every_function_taking_an_executor_has_a_case`, so a new
one cannot be forgotten.  A function that fails on Dask for a reason in a module this file's owner may not edit is
listed in :data:`KNOWN_FAILURES` (strict xfail, with the fix needed) until its owner fixes it.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import importlib
import importlib.util
import inspect
import pkgutil
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from dask_cluster import local_client

import cislunar
from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.greaves_scheeres_2021 import detection
from cislunar.utils import executors, montecarlo

distributed = pytest.importorskip("distributed", reason="the optional 'cluster' extra (dask[distributed]) is absent")

SPEC_DIR = Path(__file__).resolve().parents[1] / "reliability"


# ---------------------------------------------------------------------------------------------------------------
# discovery
# ---------------------------------------------------------------------------------------------------------------
def _discover() -> dict:
    """``{qualified name: function}`` of every public function or method in ``cislunar`` taking ``executor``."""
    found = {}
    for info in pkgutil.walk_packages(cislunar.__path__, "cislunar."):
        mod = importlib.import_module(info.name)
        for name, obj in vars(mod).items():
            if name.startswith("_") or getattr(obj, "__module__", None) != mod.__name__:
                continue
            members = [(name, obj)] if inspect.isfunction(obj) else []
            if inspect.isclass(obj):
                members += [(f"{name}.{m}", f) for m, f in vars(obj).items()
                            if not m.startswith("_") and inspect.isfunction(f)]
            for qual, fn in members:
                if "executor" in inspect.signature(fn).parameters:
                    found[f"{mod.__name__}.{qual}"] = fn
    return found


class _Spec:
    """The ``Spec`` protocol of ``tests/reliability`` (only the valid call is used here)."""

    def __init__(self, label, fn, kwargs, kinds, *, baseline=True):
        self.label, self.fn, self.kwargs, self.baseline = label, fn, kwargs, baseline


def _lazy(f):
    f._lazy = True
    return f


def _plugin_specs() -> dict:
    """``{function: kwargs}`` from the reliability plugins' valid calls (lazy values resolved when used)."""
    out = {}
    if str(SPEC_DIR) not in sys.path:  # the plugins import their shared helpers from spec_helpers.py beside them
        sys.path.insert(0, str(SPEC_DIR))
    for path in sorted(SPEC_DIR.glob("reliability_specs_*.py")):
        spec = importlib.util.spec_from_file_location(f"_dask_{path.stem}", path)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        for s in mod.specs(_Spec, _lazy):
            if not getattr(s.fn, "_lazy", False):
                out.setdefault(s.fn, s.kwargs)
    return out


FUNCTIONS = _discover()
SPECS = _plugin_specs()


# ---------------------------------------------------------------------------------------------------------------
# calls of the functions without a plugin spec (smallest meaningful sizes)
# ---------------------------------------------------------------------------------------------------------------
@functools.lru_cache(maxsize=None)
def _setup():
    """A two-window detection set-up on the 9:2 NRHO (as ``tests/reliability/test_reliability.py``'s)."""
    return detection.make_setup(em, orbits.nrho_9_2(em), detection.window_control_weight(detection.ACTIVE_POLICY),
                                1e-18, cadence_hours=8.0, window_hours=16.0, periods=0.6, n_sub=3)


def _trial(rng, scale):
    return scale * rng.standard_normal(3)


def _square(task):
    return task * task


GS21 = "cislunar.papers.greaves_scheeres_2021."
CALLS = {
    GS21 + "detection.run_detection_monte_carlo":
        lambda: dict(setup=_setup(), policy=detection.ACTIVE_POLICY, n_trials=3, seed=0, batch_size=2,
                     progress=False),
    GS21 + "detection.run_detection_monte_carlos":
        lambda: dict(jobs=[(_setup(), None, 2, 0), (_setup(), detection.ACTIVE_POLICY, 3, [1, 2])], batch_size=2),
    GS21 + "detection.run_policy_study":
        lambda: dict(setup=_setup(), policy=detection.ACTIVE_POLICY, n_h0=2, n_h1=2, n_test=1, seed=0, batch_size=2,
                     progress=False),
    GS21 + "detection.run_policy_studies":
        lambda: dict(jobs=[(_setup(), detection.ACTIVE_POLICY, 2, 2, 1, 0)], batch_size=2),
    GS21 + "detection.filter_trial_sets":
        lambda: dict(sets=[(_setup(), [detection.draw_trial(np.random.default_rng(k), _setup(), detection.ACTIVE_POLICY)
                                      for k in range(2)])]),
    GS21 + "detection_studies.run_joint_search":
        lambda: dict(system=em, orbit=orbits.nrho_9_2(em), policies={"quiet": detection.QUIET_POLICY},
                     windows_hours=(8.0,), factors=(0.3,), q_bases_km2_s3=(1e-18,), noise_urad=(10.0,),
                     burn_offsets_hours=(0.0,), n_screen=(6, 6), n_paper=(6, 8), n_boot=2, seed=0,
                     paper_zlim={"quiet": 0.022}, batch_size=2),
    GS21 + "detection_studies.run_lead_grid":
        lambda: dict(system=em, orbit=orbits.nrho_9_2(em), factors=(0.3,), noise_urad=(20.0,), magnitudes_m_s=(0.5,),
                     n_h0=10, n_h1=1, seed=0, q_base_km2_s3=1e-18, window_hours=8.0, horizon_hours=2.0),
    "cislunar.utils.montecarlo.run_monte_carlo":
        lambda: dict(trial=_trial, n_trials=7, seed=3, args=(2.0,), chunk_size=2, progress=False),
    "cislunar.utils.montecarlo.map_tasks": lambda: dict(fn=_square, tasks=range(5), progress=False),
}

@functools.lru_cache(maxsize=None)
def _short_scvx():
    """SCvx limited to 3 iterations: enough to compare every step of a solve (discretisation, information,
    convex subproblem) between serial and Dask, not to converge (the outcome is then the same SCvxError)."""
    from cislunar.guidance import scvx

    return scvx.SCvxSettings(max_iter=3)


def _short_solver(solver):
    from cislunar.papers.wolf_jones import scenarios as wj

    return wj.ScenarioSolver(solver.scenario, solver.t, solver.k_window, information=solver.information,
                             keep_out=bool(solver.constraints), settings=_short_scvx())


WJ = "cislunar.papers.wolf_jones.test_case_studies."
#: ``{qualified name: kwargs -> changed kwargs}`` applied to the plugin's valid call: work through the executor
#: where the valid call queues none, or fewer SCvx iterations (the wolf_jones case-2 solves are the slow ones).
OVERRIDES = {
    WJ + "case2_runs": lambda kw: dict(kw, seed_alphas=(0.0,), solver=_short_solver(kw["solver"])),
    WJ + "alt_grid_sweep": lambda kw: dict(kw, settings=_short_scvx()),
    WJ + "queue_keep_out_runs":
        lambda kw: dict(kw, case=dataclasses.replace(kw["case"], solver=_short_solver(kw["case"].solver))),
}

#: Functions whose result is a handle on queued work: how to wait for it.
COLLECT = {
    "cislunar.papers.wolf_jones.test_case_studies.queue_keep_out_runs":
        lambda jobs: ({d: _outcome(f) for d, f in jobs.radius_jobs.items()},
                      {k: _outcome(f) for k, f in jobs.amax_jobs.items()}),
}

#: ``{qualified name: reason and fix}``: known to fail on Dask in a module another engineer owns (strict xfail).
KNOWN_FAILURES: dict = {}

#: Not run on the cluster: takes an executor but computes nothing with it.
DESCRIBE_ONLY = {"cislunar.utils.executors.describe_executor"}


def _outcome(future):
    try:
        return future.result()
    except Exception as exc:  # noqa: BLE001 - a failed solve is an outcome, compared by type and text
        return exc


def _kwargs(qualname: str) -> dict:
    fn = FUNCTIONS[qualname]
    if qualname in CALLS:
        kw = CALLS[qualname]()
    else:
        kw = {k: (v() if getattr(v, "_lazy", False) else v) for k, v in SPECS[fn].items()}
    if qualname in OVERRIDES:
        kw = OVERRIDES[qualname](kw)
    kw.pop("executor", None)
    return kw


def _fresh(kw: dict) -> dict:
    """The same arguments, with generators copied (a run advances the generator it is given)."""
    return {k: copy.deepcopy(v) if isinstance(v, np.random.Generator) else v for k, v in kw.items()}


# ---------------------------------------------------------------------------------------------------------------
# bit-for-bit comparison
# ---------------------------------------------------------------------------------------------------------------
#: Wall-clock measurements, which differ between any two runs.
TIMING = re.compile(r"second|elapsed|wall|^t_(discretize|info|solve|hessian)$")


def differences(a, b, path="result", depth=0) -> list:
    """Where ``a`` and ``b`` differ (empty when equal bit for bit, wall-clock fields skipped)."""
    if depth > 20:
        return []
    if type(a) is not type(b):
        return [f"{path}: {type(a).__name__} vs {type(b).__name__}"]
    if isinstance(a, np.ndarray):
        if a.shape != b.shape or a.dtype != b.dtype:
            return [f"{path}: {a.dtype}{a.shape} vs {b.dtype}{b.shape}"]
        if a.dtype.kind in "biufc":
            return [] if np.array_equal(a, b, equal_nan=a.dtype.kind in "fc") else [f"{path}: values differ"]
        return [d for k, (x, y) in enumerate(zip(a.ravel(), b.ravel())) for d in differences(x, y, f"{path}[{k}]",
                                                                                              depth + 1)]
    if isinstance(a, (float, np.floating, complex, np.complexfloating)):
        return [] if a == b or (a != a and b != b) else [f"{path}: {a!r} vs {b!r}"]
    if isinstance(a, (bool, int, str, bytes, type(None), np.integer, np.bool_, range)):
        return [] if a == b else [f"{path}: {a!r} vs {b!r}"]
    if isinstance(a, BaseException):
        return ([] if str(a) == str(b) else [f"{path}: {a} vs {b}"]) + differences(vars(a), vars(b), path, depth + 1)
    if isinstance(a, dict):
        if list(a) != list(b):
            return [f"{path}: keys {list(a)} vs {list(b)}"]
        return [d for k in a if not (isinstance(k, str) and TIMING.search(k))
                for d in differences(a[k], b[k], f"{path}[{k!r}]", depth + 1)]
    if isinstance(a, (list, tuple)):
        if len(a) != len(b):
            return [f"{path}: {len(a)} vs {len(b)} items"]
        return [d for k, (x, y) in enumerate(zip(a, b)) for d in differences(x, y, f"{path}[{k}]", depth + 1)]
    if dataclasses.is_dataclass(a):
        return [d for f in dataclasses.fields(a) if not TIMING.search(f.name)
                for d in differences(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}", depth + 1)]
    if inspect.isroutine(a) or inspect.isclass(a):
        return [] if a == b or getattr(a, "__qualname__", 0) == getattr(b, "__qualname__", 1) else [f"{path}"]
    if hasattr(a, "__dict__"):
        return differences(vars(a), vars(b), path, depth + 1)
    return [] if repr(a) == repr(b) else [f"{path}: {type(a).__name__} differs"]


def test_the_comparison_notices_one_bit():
    """The comparison this module relies on: one ulp in a nested array, a field, a key or a NaN is noticed."""
    a = {"x": [np.array([1.0, np.nan]), montecarlo.TrialFailure(1, "s", ValueError("e"), "tb")], "seconds": 1.0}
    b = copy.deepcopy(a)
    b["seconds"] = 2.0
    assert differences(a, b) == []
    b["x"][0][0] = np.nextafter(1.0, 2.0)
    assert differences(a, b)
    c = copy.deepcopy(a)
    c["x"][1] = montecarlo.TrialFailure(2, "s", ValueError("e"), "tb")
    assert differences(a, c)
    assert differences(a, {**a, "y": 1})


# ---------------------------------------------------------------------------------------------------------------
# the cluster and the tests
# ---------------------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def client():
    with local_client(__name__) as cl:
        yield cl


def test_every_function_taking_an_executor_has_a_case():
    missing = [q for q, fn in FUNCTIONS.items() if q not in CALLS and fn not in SPECS and q not in DESCRIBE_ONLY]
    assert not missing, f"functions taking an executor with no Dask case (add one to CALLS): {missing}"
    stale = sorted((set(CALLS) | set(OVERRIDES) | set(COLLECT) | set(KNOWN_FAILURES)) - set(FUNCTIONS))
    assert not stale, f"cases for functions that no longer take an executor: {stale}"
    assert len(FUNCTIONS) >= 20  # the walk found the package's functions (not an empty import)


def test_describe_executor_names_the_cluster(client):
    assert executors.describe_executor(client).startswith("Dask tcp://")


@pytest.mark.parametrize("qualname", sorted(set(FUNCTIONS) - DESCRIBE_ONLY))
def test_runs_on_dask_bit_identical_to_serial(qualname, client, request):
    if qualname in KNOWN_FAILURES:
        request.applymarker(pytest.mark.xfail(strict=True, reason=KNOWN_FAILURES[qualname]))
    fn = FUNCTIONS[qualname]
    if qualname not in CALLS and fn not in SPECS:
        pytest.fail(f"{qualname} takes an executor and has no Dask case (add one to CALLS)")
    kw = _kwargs(qualname)
    collect = COLLECT.get(qualname, lambda r: r)
    serial = collect(fn(**_fresh(kw), executor=None))
    on_dask = collect(fn(**_fresh(kw), executor=client))
    diff = differences(serial, on_dask)
    assert not diff, f"{qualname}: Dask and serial results differ at {diff[:5]}"

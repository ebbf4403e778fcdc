import dataclasses
import fcntl
import json
import os
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")
os.environ.setdefault("JUPYTER_PREFER_ENV_PATH", "1")

try:
    from hypothesis import settings

    settings.register_profile("ci", deadline=None, max_examples=40, derandomize=True, database=None)
    settings.load_profile("ci")
except ImportError:  # pragma: no cover
    pass


def selected_notebooks():
    """Notebook sources the notebook and book tests use: all, or those named in ``CISLUNAR_TEST_NOTEBOOKS``.

    ``CISLUNAR_TEST_NOTEBOOKS=01,04 pytest tests/test_book.py`` builds and checks a book of two notebooks only (for
    working on the book); ``make test`` leaves it unset and covers every notebook.
    """
    from cislunar.publish import notebooks
    names = [n.strip() for n in os.environ.get("CISLUNAR_TEST_NOTEBOOKS", "").split(",") if n.strip()]
    return notebooks.discover(names or None)


class QuickRuns:
    """Every notebook executed in quick mode at most once per pytest session, shared by all xdist workers.

    The runs go to ``<session tmp>/cislunar-quick/build`` (never the repository's ``build/``, which only holds full
    runs).  A lock file per notebook makes a worker that wants a notebook another worker is running wait for it
    instead of running it twice; the outcome (closing table, or the failure message) is kept in a JSON file that the
    notebook tests and the book tests both read.
    """

    def __init__(self, root: Path):
        self.root = root
        self.build = root / "build"
        self.state = root / "state"
        self.state.mkdir(parents=True, exist_ok=True)

    def run(self):
        """The session's one run (shared by both xdist workers), so its quick build is a build of one run."""
        from cislunar.publish import provenance
        from cislunar.utils import paths

        path = self.state / "run.json"
        with open(self.state / "run.lock", "a+") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not path.is_file():
                run = provenance.new_run(quick=True, seed=0, root=paths.repo_root())
                path.write_text(json.dumps(dataclasses.asdict(run)))
        return provenance.RunInfo(**json.loads(path.read_text()))

    def _run(self, source: Path) -> dict:
        from cislunar.publish import notebooks
        try:
            res = notebooks.run_notebook(source, quick=True, seed=0, output_dir=self.build, run=self.run())
        except Exception as exc:  # recorded here, reported by the notebook's own test
            return {"ok": False, "error": f"{type(exc).__name__}: {exc}"}
        return {"ok": True, "report": res.report_markdown, "seconds": res.seconds}

    def get(self, source: Path, *, wait: bool = True) -> dict | None:
        """Outcome of ``source`` in quick mode, running it first if nobody has; ``None`` if busy and not ``wait``."""
        status = self.state / f"{source.stem}.json"
        with open(self.state / f"{source.stem}.lock", "a+") as lock:
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
            except BlockingIOError:
                return None
            if status.is_file():
                return json.loads(status.read_text())
            data = self._run(source)
            tmp = status.with_suffix(".tmp")
            tmp.write_text(json.dumps(data))
            os.replace(tmp, status)
            return data

    def all(self, sources) -> dict:
        """Outcomes of all ``sources``: first those no other worker has started, then wait for the rest."""
        done = {}
        for src in sources:
            res = self.get(src, wait=False)
            if res is not None:
                done[src.stem] = res
        for src in sources:
            if src.stem not in done:
                done[src.stem] = self.get(src)
        return done


# --------------------------------------------------------------------------------------------- xdist scheduling
# `make test` runs `pytest -n 2 --dist loadgroup`.  Three rules keep the two workers busy until the end:
# 1. Tests that share a module-scoped fixture (a converged SCvx sweep, a torus solve) form one xdist group per module,
#    so the fixture is computed once instead of once per worker.
# 2. Work units are handed out in collection order (xdist's default reorders them by size, which put the six book
#    tests first: their worker then ran every notebook alone while the other did unit tests): the notebook runs come
#    first, longest first, then the module groups, then the book tests (every notebook has run by then), and the
#    single tests last, so that many small units even out the workers' finish.
# 3. The expected quick-mode seconds of each notebook come from the last run (pytest's cache) or, on a fresh clone,
#    from the table below (quick mode on an idle core, issue 12 budget <= 30 s each).
# 4. Longest first inside each rank too: every work unit's seconds (a group's summed over its tests) of the last
#    `-n 2 --dist loadgroup` run are kept in pytest's cache, and the groups and the single tests are handed out in
#    decreasing expected seconds (units never timed keep collection order: groups first, single tests last), so
#    the last units of the run are the shortest ones and the two workers finish together.
QUICK_SECONDS = {"01": 7, "02": 8, "03": 9, "04": 7, "05": 30, "06": 30, "07": 20, "08": 21, "09": 30, "09b": 30,
                 "10": 30, "11": 30, "12": 30}
_CACHE_KEY = "cislunar/quick-notebook-seconds"
_UNIT_KEY = "cislunar/work-unit-seconds"


def pytest_configure(config):
    if hasattr(config.option, "loadscopereorder"):
        config.option.loadscopereorder = False  # keep the order of pytest_collection_modifyitems (rule 2)


def _unit(nodeid: str, group: str | None) -> str:
    """The xdist work unit of a test: its group (all its tests run in one worker), else the test itself."""
    return f"group:{group}" if group is not None else nodeid


def _expected_seconds(config, stem: str) -> float:
    cached = config.cache.get(_CACHE_KEY, {}) if getattr(config, "cache", None) is not None else {}
    if stem in cached:
        return float(cached[stem])
    return float(QUICK_SECONDS.get(stem.split("_")[0], 60))  # an unknown notebook: assume long, start it early


@pytest.hookimpl(tryfirst=True)  # before xdist's own hook, which turns xdist_group marks into scheduling scopes
def pytest_collection_modifyitems(config, items):
    def module_group(item):
        info = getattr(item, "_fixtureinfo", None)
        if info is None or item.get_closest_marker("xdist_group"):
            return None
        for defs in info.name2fixturedefs.values():
            fd = defs[-1]
            if fd.scope == "module" and fd.baseid.endswith(".py"):  # defined in the test module itself
                return f"module-fixtures:{item.path.name}"
        return None

    units = config.cache.get(_UNIT_KEY, {}) if getattr(config, "cache", None) is not None else {}

    def rank(item):
        marker = item.get_closest_marker("xdist_group")
        callspec = getattr(item, "callspec", None)
        source = callspec.params.get("source") if callspec is not None else None
        if item.get_closest_marker("notebook") and marker is None and isinstance(source, Path):
            return (0, -_expected_seconds(config, source.stem))  # one notebook per unit, longest first
        if marker is None:  # single tests last, longest first (rule 4): the small ones even out the finish
            return (3, -float(units.get(_unit(item.nodeid, None), 0.0)))
        if marker.args and marker.args[0] == "book":
            return (2, 0.0)
        return (1, -float(units.get(_unit(item.nodeid, _group_name(item)), float("inf"))))

    for item in items:
        group = module_group(item)
        if group is not None:
            item.add_marker(pytest.mark.xdist_group(group))
    items[:] = [it for _, it in sorted(enumerate(items), key=lambda p: (rank(p[1]), p[0]))]


def _group_name(item) -> str | None:
    """The name xdist's loadgroup gives the unit of ``item`` (its ``xdist_group`` marks joined), or ``None``."""
    names = sorted({str(m.args[0] if m.args else m.kwargs.get("name", "default"))
                    for m in item.iter_markers("xdist_group")})
    return "_".join(names) if names else None


@pytest.hookimpl(trylast=True, specname="pytest_collection_modifyitems")
def pytest_collection_modifyitems_xdist_scopes(config, items):
    """Make ``--dist loadgroup`` group again: xdist 3.8 marks a group by appending ``@group`` to ``item._nodeid``,
    which pytest 9 no longer reads (the node id lives in ``item._id``), so every test was its own scope and
    ``xdist_group`` had no effect.  Done here on the worker side, as xdist intends, when a worker runs loadgroup."""
    if not getattr(config.option, "loadgroup", False):  # set on xdist workers running --dist loadgroup
        return
    from _pytest.nodeid import NodeId

    for item in items:
        group = _group_name(item)
        if group is not None and "@" not in item.nodeid and hasattr(item, "_id"):
            item._id = NodeId.parse(f"{item.nodeid}@{group}")


_UNIT_SECONDS: dict = {}  # controller side: seconds of each work unit run in this session (rule 4)


def pytest_runtest_logreport(report):
    """Add a test phase's seconds to its work unit (on the xdist controller, whose node ids carry ``@group``)."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        return
    nodeid, _, group = report.nodeid.rpartition("@") if "@" in report.nodeid else (report.nodeid, "", "")
    key = _unit(nodeid, group or None)
    _UNIT_SECONDS[key] = _UNIT_SECONDS.get(key, 0.0) + float(getattr(report, "duration", 0.0) or 0.0)


def pytest_sessionfinish(session):
    """Remember how long each work unit (rule 4) and each quick notebook (rule 3, from the shared run records of
    this session) took."""
    if os.environ.get("PYTEST_XDIST_WORKER") or getattr(session.config, "cache", None) is None:
        return
    if getattr(session.config.option, "dist", "no") == "loadgroup" and _UNIT_SECONDS:  # rule 4, `make test` only
        units = dict(session.config.cache.get(_UNIT_KEY, {}))
        units.update({k: round(v, 2) for k, v in _UNIT_SECONDS.items()})
        session.config.cache.set(_UNIT_KEY, units)
    factory = getattr(session.config, "_tmp_path_factory", None)
    if factory is None or factory._basetemp is None:
        return
    state = factory.getbasetemp() / "cislunar-quick" / "state"
    seconds = dict(session.config.cache.get(_CACHE_KEY, {}))
    for status in state.glob("*.json") if state.is_dir() else ():
        data = json.loads(status.read_text())
        if data.get("ok") and "seconds" in data:
            seconds[status.stem] = round(float(data["seconds"]), 1)
    session.config.cache.set(_CACHE_KEY, seconds)


@pytest.fixture(scope="session")
def quick_runs(tmp_path_factory) -> QuickRuns:
    """The session's shared quick-mode notebook runs (one directory for all xdist workers)."""
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # the workers' basetemps are siblings under the session's directory
    root = base / "cislunar-quick"
    root.mkdir(parents=True, exist_ok=True)
    return QuickRuns(root)

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

    settings.register_profile("ci", deadline=None, max_examples=40, derandomize=True)
    settings.load_profile("ci")
except ImportError:  # pragma: no cover
    pass


def selected_notebooks():
    """Notebook sources the notebook and book tests use: all, or those named in ``CISLUNAR_TEST_NOTEBOOKS``.

    ``CISLUNAR_TEST_NOTEBOOKS=01,04 pytest tests/test_book.py`` builds and checks a book of two notebooks only (for
    working on the book); ``make test`` leaves it unset and covers every notebook.
    """
    from cislunar import notebooks

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

    def _run(self, source: Path) -> dict:
        from cislunar import notebooks

        try:
            res = notebooks.run_notebook(source, quick=True, seed=0, output_dir=self.build)
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


@pytest.fixture(scope="session")
def quick_runs(tmp_path_factory) -> QuickRuns:
    """The session's shared quick-mode notebook runs (one directory for all xdist workers)."""
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # the workers' basetemps are siblings under the session's directory
    root = base / "cislunar-quick"
    root.mkdir(parents=True, exist_ok=True)
    return QuickRuns(root)

"""Where a build came from: the run, its records, and the audit that refuses a partial or mixed build.

Every run of the notebook runner gets a :class:`RunInfo` (run id, commit, mode, seed, start time).  Each notebook
that runs leaves a record ``<build>/runs/<name>.json``; its executed notebook carries the same run in its metadata
(``metadata["cislunar"]``) and its section of ``report.md`` says it in a provenance line under its heading.
:func:`audit_build` reads all three and lists what makes a build unfit to publish: a notebook missing or failed, a
notebook from another run (a mixed build), or metadata that disagrees with its record.  The book refuses any build
with a problem (:class:`IncompleteBuildError`), naming what is missing.
"""

from __future__ import annotations

import json
import os
import subprocess
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from cislunar.utils import validation

__all__ = ["RunInfo", "IncompleteBuildError", "new_run", "git_commit", "write_record", "read_records",
           "provenance_line", "parse_provenance_line", "audit_build", "METADATA_KEY"]

#: Key of the run information in an executed notebook's metadata.
METADATA_KEY = "cislunar"


@dataclass(frozen=True)
class RunInfo:
    """One run of the notebook runner.

    Attributes
    ----------
    run_id : str
        ``YYYYmmddTHHMMSSZ-xxxx`` (UTC start time and four random hex digits).
    commit : str
        Short commit hash of the checkout, ``+dirty`` when it had uncommitted changes, or ``unknown``.
    mode : {"full", "quick"}
    seed : int
    started : str
        Start time, ISO 8601 UTC.
    """

    run_id: str
    commit: str
    mode: str
    seed: int
    started: str

    def __post_init__(self):
        if self.mode not in ("full", "quick"):
            raise ValueError(f"mode must be 'full' or 'quick'; got {self.mode!r}")


class IncompleteBuildError(RuntimeError):
    """A build that is partial, failed or mixed; ``problems`` lists each reason (a notebook and what is wrong)."""

    def __init__(self, build, problems):
        self.build = str(build)
        self.problems = list(problems)
        super().__init__(f"{self.build} is not a complete build of one run:\n  " + "\n  ".join(self.problems))

    def __reduce__(self):
        return (type(self), (self.build, self.problems))


def _folder(value, name: str) -> Path:
    if not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{name} must be a path (str or os.PathLike); got {type(value).__name__}")
    if not str(value).strip():
        raise ValueError(f"{name} must be a non-empty path")
    return Path(value)


def git_commit(root) -> str:
    """Short commit of the checkout at ``root`` (``+dirty`` with uncommitted changes), or ``unknown``."""
    root = _folder(root, "root")
    try:
        head = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], cwd=root, capture_output=True, text=True,
                              timeout=10)
        if head.returncode != 0:
            return "unknown"
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root,
                               capture_output=True, text=True, timeout=10)
        return head.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def new_run(*, quick: bool, seed: int, root) -> RunInfo:
    """A fresh :class:`RunInfo` for a run from the checkout at ``root``."""
    quick = validation.boolean(quick, "quick")
    seed = validation.integer(seed, "seed", minimum=0)
    now = time.gmtime()
    run_id = time.strftime("%Y%m%dT%H%M%SZ", now) + "-" + os.urandom(2).hex()
    return RunInfo(run_id, git_commit(root), "quick" if quick else "full", int(seed),
                   time.strftime("%Y-%m-%dT%H:%M:%SZ", now))


def provenance_line(run: RunInfo, seconds: float) -> str:
    """The line under a report section's heading: mode, time, run, commit and start."""
    validation.instance(run, "run", RunInfo)
    seconds = validation.positive(seconds, "seconds", allow_zero=True)
    return (f"*{run.mode} mode · {seconds:.0f} s · run {run.run_id} · commit {run.commit} · "
            f"started {run.started}*")


def parse_provenance_line(text: str) -> dict | None:
    """``{"mode", "run_id", "commit"}`` from the first provenance line of a report section, else ``None``."""
    validation.instance(text, "text", str)
    for line in text.splitlines():
        if line.startswith("*") and " mode · " in line and " · run " in line:
            parts = line.strip("*").split(" · ")
            out = {"mode": parts[0].split()[0]}
            for p in parts[1:]:
                if p.startswith("run "):
                    out["run_id"] = p[4:]
                elif p.startswith("commit "):
                    out["commit"] = p[7:]
            return out
    return None


def write_record(build, name: str, run: RunInfo, *, status: str, seconds: float, error: str = "") -> Path:
    """Write ``<build>/runs/<name>.json`` atomically: this notebook's outcome in ``run``."""
    build = _folder(build, "build")
    validation.instance(name, "name", str)
    if not name or "/" in name or name.startswith("."):
        raise ValueError(f"name must be a notebook name (no path); got {name!r}")
    validation.instance(run, "run", RunInfo)
    seconds = validation.positive(seconds, "seconds", allow_zero=True)
    validation.instance(error, "error", str)
    if status not in ("ok", "failed", "interrupted"):
        raise ValueError(f"status must be 'ok', 'failed' or 'interrupted'; got {status!r}")
    folder = build / "runs"
    folder.mkdir(parents=True, exist_ok=True)
    data = dict(asdict(run), notebook=name, status=status, seconds=round(float(seconds), 1), error=error,
                finished=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()))
    out = folder / f"{name}.json"
    tmp = folder / f".{name}.json.{os.getpid()}"
    tmp.write_text(json.dumps(data, indent=1))
    os.replace(tmp, out)
    return out


def read_records(build) -> dict:
    """``{notebook name: record dict}`` of ``<build>/runs/*.json``."""
    folder = _folder(build, "build") / "runs"
    if not folder.is_dir():
        return {}
    return {p.stem: json.loads(p.read_text()) for p in sorted(folder.glob("*.json"))}


def audit_build(build, expected) -> list[str]:
    """What keeps ``build`` from being a complete build of one run, as a list of problems (empty: fit to publish).

    Parameters
    ----------
    build : path-like
        A build directory (``notebooks/``, ``report/``, ``runs/``).
    expected : iterable of str
        Names of every notebook the build must hold.
    """
    build = _folder(build, "build")
    if isinstance(expected, (str, bytes)) or not hasattr(expected, "__iter__"):
        raise TypeError(f"expected must be an iterable of notebook names; got {type(expected).__name__}")
    expected = list(expected)
    if not all(isinstance(n, str) for n in expected):
        raise TypeError("expected must hold notebook names (str)")
    records = read_records(build)
    problems = []
    runs = {}
    for name in expected:
        rec = records.get(name)
        executed = build / "notebooks" / f"{name}.ipynb"
        section = build / "report" / f"{name}.md"
        if rec is None:
            problems.append(f"{name}: missing (no record of a run in {build / 'runs'})")
            continue
        if rec.get("status") != "ok":
            problems.append(f"{name}: {rec.get('status')} in run {rec.get('run_id')}"
                            + (f" ({rec['error'][:200]})" if rec.get("error") else ""))
            continue
        runs.setdefault(rec["run_id"], []).append(name)
        if not executed.is_file():
            problems.append(f"{name}: the executed notebook is missing")
        else:
            meta = json.loads(executed.read_text()).get("metadata", {}).get(METADATA_KEY, {})
            if meta.get("run_id") != rec["run_id"]:
                problems.append(f"{name}: the executed notebook is from run {meta.get('run_id')}, its record from "
                                f"run {rec['run_id']}")
        if not section.is_file():
            problems.append(f"{name}: its report section is missing")
        else:
            prov = parse_provenance_line(section.read_text()) or {}
            if prov.get("run_id") != rec["run_id"]:
                problems.append(f"{name}: its report section is from run {prov.get('run_id')}, its record from "
                                f"run {rec['run_id']}")
    if len(runs) > 1:
        detail = "; ".join(f"run {r}: {', '.join(sorted(n))}" for r, n in sorted(runs.items()))
        problems.append(f"mixed build: sections come from {len(runs)} runs ({detail})")
    modes = {records[n]["mode"] for ns in runs.values() for n in ns}
    if len(modes) > 1:
        problems.append(f"mixed build: modes {sorted(modes)}")
    return problems

"""Malformed-argument specs for the publishing wing's newer modules and the executor helper (plugin of
tests/reliability/test_reliability.py): claims and their criteria, provenance records, chapter statistics."""

from __future__ import annotations

import functools
from pathlib import Path

from cislunar.publish import chapters, claims, provenance
from cislunar.utils import executors, paths

MODULES = [claims, provenance, chapters, executors]
EXEMPT = {
    "main": "the command line: argparse refuses bad arguments with its own usage message",
    "describe_executor": "describes any object it is given (an executor, a client or None); never raises",
}


@functools.lru_cache(maxsize=None)
def run():
    return provenance.new_run(quick=True, seed=0, root=paths.repo_root())


@functools.lru_cache(maxsize=None)
def a_source():
    return sorted((paths.repo_root() / "notebooks").glob("[0-9]*.py"))[0]


def specs(Spec, lazy):
    s = []
    S = Spec
    s.append(S("printed_tolerance", claims.printed_tolerance, dict(printed="1.2"), dict(printed="instance_str")))
    s.append(S("status_of", claims.status_of, dict(kind="comparison", criterion_holds=True, tuned=False),
               dict(kind="choice")))
    s.append(S("Claim", claims.Claim, dict(quantity="q", paper=1.0, criterion=claims.Within(1.0, 0.1),
                                            kind="comparison", tuned="", source="", reason=""),
               dict(quantity="instance_str", criterion="criterion", kind="choice", tuned="instance_str",
                    source="instance_str", reason="instance_str")))
    s.append(S("Claim.judge", lazy(lambda: claims.Claim("q", 1.0, claims.Within(1.0, 0.1)).judge),
               dict(measured=1.0, shown=None, note="", standard_error=0.0, reason=""),
               dict(note="instance_str", standard_error="nonneg", reason="instance_str")))
    s.append(S("Within", claims.Within, dict(target=1.0, tol=0.1, relative=False, n_sigma=0.0),
               dict(target="real", tol="nonneg", n_sigma="nonneg")))
    s.append(S("AtMost", claims.AtMost, dict(limit=1.0, n_sigma=0.0), dict(limit="real", n_sigma="nonneg")))
    s.append(S("AtLeast", claims.AtLeast, dict(limit=1.0, n_sigma=0.0), dict(limit="real", n_sigma="nonneg")))
    s.append(S("Between", claims.Between, dict(lo=0.0, hi=1.0), dict(lo="real", hi="real")))
    s.append(S("Holds", claims.Holds, dict(test="it holds", expected=True), dict(test="instance_str")))
    s.append(S("git_commit", provenance.git_commit, dict(root=lazy(paths.repo_root)), dict(root="path")))
    s.append(S("new_run", provenance.new_run, dict(quick=True, seed=0, root=lazy(paths.repo_root)),
               dict(quick="bool", seed="int0", root="path")))
    s.append(S("provenance_line", provenance.provenance_line, dict(run=lazy(run), seconds=1.0),
               dict(run="instance", seconds="nonneg")))
    s.append(S("parse_provenance_line", provenance.parse_provenance_line, dict(text="*quick mode · 1 s · run x*"),
               dict(text="instance_str")))
    s.append(S("write_record", provenance.write_record,
               dict(build=lazy(lambda: Path(paths.scratch_dir().parent / ".reliability-never-created")),
                    name="01_a", run=lazy(run), status="ok", seconds=1.0, error=""),
               dict(name="instance_str", run="instance", status="choice", seconds="nonneg", error="instance_str"),
               baseline=False))
    s.append(S("read_records", provenance.read_records, dict(build=lazy(lambda: paths.repo_root() / "notebooks")),
               dict(build="path")))
    s.append(S("audit_build", provenance.audit_build,
               dict(build=lazy(lambda: paths.repo_root() / "notebooks"), expected=["01_a"]),
               dict(build="path", expected="names")))
    s.append(S("chapter_statistics", chapters.chapter_statistics, dict(source=lazy(a_source)),
               dict(source="path")))
    s.append(S("statistics_table", chapters.statistics_table, dict(sources=lazy(lambda: [a_source()])),
               dict(sources="iterable")))
    s.append(S("open_executor", executors.open_executor, dict(workers=1, scheduler=""),
               dict(workers="int1", scheduler="instance_str")))
    return s

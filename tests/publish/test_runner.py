"""The command-line runner: parameters, a staging folder that replaces the build only when everything ran,
provenance in every output, per-cell time limits, and Ctrl-C that ends every process of the run."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from cislunar.publish import notebooks, provenance

pytestmark = pytest.mark.xdist_group("runner")

HEADER = '# %% tags=["parameters"]\nQUICK = False\nSEED = 0\nOUTPUT_DIR = ""\n{extra}\n'
TABLE = ("# %%\nfrom cislunar.publish.claims import Claim\nfrom cislunar.publish.report import ComparisonTable\n"
         "ComparisonTable('t').add(Claim('x [-]', kind='derived').judge({value})).display()\n")


def source(folder: Path, name: str, body: str = "", extra: str = "", value: str = "1") -> Path:
    path = folder / f"{name}.py"
    path.write_text(HEADER.format(extra=extra) + ("\n# %%\n" + body + "\n" if body else "") + "\n"
                    + TABLE.format(value=value))
    return path


def test_parameters_are_parsed_and_checked(tmp_path):
    assert notebooks.parse_parameter("N_NODES=24") == ("N_NODES", 24)
    assert notebooks.parse_parameter("SIGMAS=(1e-3, 2)") == ("SIGMAS", (1e-3, 2))
    assert notebooks.parse_parameter("LABEL=dro") == ("LABEL", "dro")
    with pytest.raises(ValueError, match="NAME=VALUE"):
        notebooks.parse_parameter("N_NODES")
    with pytest.raises(ValueError, match="identifier"):
        notebooks.parse_parameter("2N=3")
    src = source(tmp_path, "90_a", extra="N_NODES = 12\nWORKERS = 2")
    assert set(notebooks.parameter_names(src)) == {"QUICK", "SEED", "OUTPUT_DIR", "N_NODES", "WORKERS"}
    assert notebooks._workers_asked(src, {}) == 2 and notebooks._workers_asked(src, {"WORKERS": 1}) == 1
    picks = source(tmp_path, "90_b", extra="WORKERS = None")
    assert notebooks._workers_asked(picks, {}, quick=True) == 1
    assert notebooks._workers_asked(picks, {}, quick=False) == 2
    assert notebooks._workers_asked(source(tmp_path, "90_c"), {}, quick=False) == 1
    with pytest.raises(ValueError, match="has no parameter N_NODE"):
        notebooks.run_notebook(src, quick=True, output_dir=tmp_path / "b", parameters={"N_NODE": 3})


def test_fresh_build_starts_whole_machine_notebooks_first_then_longest_last_run_first(tmp_path):
    a = source(tmp_path, "01_short")
    b = source(tmp_path, "02_wide", extra="WORKERS = None")  # QUICK picks: 2 processes in full mode
    c = source(tmp_path, "03_short")
    d = source(tmp_path, "04_wide", extra="WORKERS = 2")
    fresh = {s.stem: None for s in (a, b, c, d)}
    assert [s.stem for s in notebooks._run_order([a, b, c, d], fresh, {}, quick=False)] == \
        ["02_wide", "04_wide", "01_short", "03_short"]
    # quick mode: QUICK's pick is one process, so only the explicit WORKERS = 2 moves; WORKERS=1 given by the
    # reader keeps the sources' order
    assert notebooks._run_order([a, b, c, d], fresh, {}, quick=True) == [d, a, b, c]
    assert notebooks._run_order([a, b, c, d], fresh, {"WORKERS": 1}, quick=False) == [a, b, c, d]
    # with a last run, its time decides, whatever the processes (03_short, never run here: the 60 s default)
    last = {"01_short": 300.0, "02_wide": 20.0, "03_short": None, "04_wide": 90.0}
    assert [s.stem for s in notebooks._run_order([a, b, c, d], last, {}, quick=False)] == \
        ["01_short", "04_wide", "03_short", "02_wide"]


def test_a_parameter_changes_the_output_and_provenance_is_recorded(tmp_path):
    src = source(tmp_path, "90_param", extra="N_NODES = 12", body="print('nodes', N_NODES)",
                 value="N_NODES")
    res = notebooks.run_notebook(src, quick=True, output_dir=tmp_path / "b", parameters={"N_NODES": 7})
    text = res.executed_path.read_text()
    assert "nodes 7" in text and "nodes 12" not in text
    meta = json.loads(text)["metadata"]["cislunar"]
    rec = provenance.read_records(tmp_path / "b")["90_param"]
    assert meta["run_id"] == rec["run_id"] and rec["status"] == "ok" and meta["mode"] == "quick"
    section = (tmp_path / "b" / "report" / "90_param.md").read_text()
    assert provenance.parse_provenance_line(section)["run_id"] == rec["run_id"]
    assert "| x [-] | - | 7 | derived |" in section
    assert provenance.audit_build(tmp_path / "b", ["90_param"]) == []


def test_a_hung_cell_ends_with_an_error_naming_the_notebook_and_cell(tmp_path):
    src = source(tmp_path, "91_hang", body="import time\ntime.sleep(60)")
    start = time.monotonic()
    with pytest.raises(notebooks.NotebookFailure, match=r"91_hang: cell \d+ .*'import time'.*time limit of 2 s"):
        notebooks.run_notebook(src, quick=True, output_dir=tmp_path / "b", timeout=2)
    assert time.monotonic() - start < 40
    assert provenance.read_records(tmp_path / "b")["91_hang"]["status"] == "failed"


def test_the_build_is_replaced_only_when_everything_ran(tmp_path):
    ok_a, ok_b = source(tmp_path, "92_a"), source(tmp_path, "92_b", value="2")
    target = tmp_path / "build-quick"
    log = io.StringIO()
    assert notebooks.run_all([ok_a, ok_b], quick=True, output_dir=target, out=log, heartbeat=0) == 0
    assert provenance.audit_build(target, ["92_a", "92_b"]) == []
    first = provenance.read_records(target)["92_a"]["run_id"]
    assert "Run " + first in (target / "report.md").read_text()
    assert (target / "logs" / "92_a.log").is_file()
    assert not list(tmp_path.glob("build-quick.staging-*"))
    # a failing notebook: the previous build stays as it was, the attempt is set aside and says what is missing
    bad = source(tmp_path, "92_b", body="raise ValueError('boom')")
    assert notebooks.run_all([ok_a, bad], quick=True, output_dir=target, out=log, heartbeat=0) == 1
    assert provenance.read_records(target)["92_a"]["run_id"] == first
    incomplete = tmp_path / "build-quick-incomplete"
    report = (incomplete / "report.md").read_text()
    assert "**Incomplete build.**" in report and "92_b" in report
    problems = provenance.audit_build(incomplete, ["92_a", "92_b"])
    assert any(p.startswith("92_b: failed") for p in problems)


DRIVER = textwrap.dedent("""
    import sys
    from pathlib import Path
    from cislunar.publish import notebooks
    srcs = [Path(p) for p in sys.argv[2:]]
    sys.exit(notebooks.run_all(srcs, quick=True, output_dir=sys.argv[1], heartbeat=0))
""")


def test_sigint_mid_notebook_ends_every_process_and_leaves_the_build(tmp_path):
    """SIGINT while a notebook's pool worker runs: exit 130 within seconds, no process of the run survives, the
    previous build untouched, no temporary folder left."""
    target = tmp_path / "build-quick"
    done = source(tmp_path, "93_done")
    # the previous build is written by hand (a record is what the runner would replace): running it through
    # run_all too cost a child process and a kernel, and test_the_build_is_replaced_only_when_everything_ran
    # already checks what run_all writes
    earlier = provenance.new_run(quick=True, seed=0, root=tmp_path)
    provenance.write_record(target, "93_done", earlier, status="ok", seconds=1.0)
    (target / "report.md").write_text("earlier build\n")
    before = provenance.read_records(target)
    pids = tmp_path / "pids.txt"
    body = (f"import os, subprocess, sys, time\n"
            f"worker = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(120)'])\n"
            f"open({str(pids)!r}, 'w').write(f'{{os.getpid()}} {{worker.pid}}')\n"
            f"time.sleep(120)")
    slow = source(tmp_path, "93_slow", body=body)
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    env = dict(os.environ, TMPDIR=str(scratch))
    proc = subprocess.Popen([sys.executable, "-c", DRIVER, str(target), str(done), str(slow)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    deadline = time.monotonic() + 120
    while not pids.exists() or len(pids.read_text().split()) < 2:
        assert time.monotonic() < deadline and proc.poll() is None, proc.stdout.read() if proc.poll() else ""
        time.sleep(0.2)
    kernel, worker = (int(x) for x in pids.read_text().split())
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    output, _ = proc.communicate(timeout=60)
    assert proc.returncode == 130, output
    assert time.monotonic() - sent < 15, output
    time.sleep(0.5)
    import psutil

    for pid in (kernel, worker):
        assert not psutil.pid_exists(pid) or psutil.Process(pid).status() == psutil.STATUS_ZOMBIE, pid
    assert provenance.read_records(target) == before
    assert (target / "report.md").read_text() == "earlier build\n"
    assert list(scratch.iterdir()) == [], list(scratch.iterdir())
    import glob
    left = [d for d in glob.glob('/tmp/cl-*/spec.json') if str(slow) in Path(d).read_text()]
    assert not left, left
    rec = provenance.read_records(tmp_path / "build-quick-incomplete")
    assert rec["93_slow"]["status"] == "interrupted"


def test_status_lines_give_an_estimate_only_from_an_earlier_run(tmp_path):
    # 1 s in the cell (the child's start-up alone spans several 0.5 s beats): long enough for status lines
    src = source(tmp_path, "97_wait", body="import time\ntime.sleep(1.0)")
    target = tmp_path / "build-quick"
    first, second = io.StringIO(), io.StringIO()
    assert notebooks.run_all([src], quick=True, output_dir=target, out=first, heartbeat=0.5) == 0
    beats = [line for line in first.getvalue().splitlines() if line.startswith("[97_wait]") and " s: " in line]
    assert beats and not any("of ~" in line or "last run" in line for line in beats)  # never run here: no guess
    seconds = provenance.read_records(target)["97_wait"]["seconds"]
    assert notebooks.run_all([src], quick=True, output_dir=target, out=second, heartbeat=0.5) == 0
    assert f"last run {seconds:.0f} s" in second.getvalue()
    assert f"of ~{seconds:.0f} s (last run)" in second.getvalue()


def test_child_skips_the_iri_grammar_and_notebook_validation_still_works():
    # the runner child marks rfc3987_syntax absent (0.8 s of grammar compilation at import); jsonschema must then
    # load without it and nbformat must still accept a valid notebook and reject an invalid one
    code = textwrap.dedent("""
        import sys
        from cislunar.publish import notebooks
        notebooks._skip_iri_grammar()
        import jsonschema, nbformat, papermill, jupytext
        assert sys.modules["rfc3987_syntax"] is None
        nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("1 + 1")])
        nbformat.validate(nb)
        nb.cells[0]["cell_type"] = "not a cell type"
        try:
            nbformat.validate(nb)
        except nbformat.ValidationError:
            print("rejected")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "rejected"

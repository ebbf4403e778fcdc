"""Execute the literate notebooks headless and gather their paper-vs-reproduction tables.

Usage::

    python -m cislunar.publish.notebooks                 # every notebook at full fidelity into build/ (make reproduce)
    python -m cislunar.publish.notebooks --quick         # every notebook in quick mode into build-quick/
    python -m cislunar.publish.notebooks --quick 01 02   # a selection, by number or name prefix
    python -m cislunar.publish.notebooks 05 -p N_NODES=24 --timeout 600 --log-output

The command line runs each notebook in a child process of its own session, two at a time on a two-core machine
(``--jobs``; a notebook whose ``WORKERS`` parameter asks for several processes runs alone), with its log in
``<build>/logs/<name>.log`` and a status line per notebook every few seconds (the last line it printed, the time
so far and the time it took last run).  A run writes into a staging folder ``<build>.staging-<run id>`` and
replaces the build only when every notebook succeeded; otherwise the build is left untouched and the staging
folder becomes ``<build>-incomplete`` with a report that lists each missing and failed notebook.  Ctrl-C (or
SIGTERM) ends every kernel and worker process the run started, removes their temporary folders and exits 130 within
seconds.  Every record, executed notebook and report section says which run and commit made it
(:mod:`cislunar.publish.provenance`).

Each ``notebooks/NN_topic.py`` (jupytext py:percent) is converted to ``.ipynb`` and executed with papermill on the
``python3`` kernel with the parameters ``QUICK``, ``SEED`` and ``OUTPUT_DIR``.  Executed notebooks land in
``<build>/notebooks/``, figures in ``<build>/figures/`` (written by the notebooks through
:func:`cislunar.publish.plotting.save_figure`), each notebook's closing table in ``<build>/report/NN_topic.md``, and all
tables present are assembled into ``<build>/report.md``, which says in which mode they ran.  A failing cell fails
the command, naming the notebook and the cell.

``build/`` only ever holds full runs: quick runs default to ``build-quick/`` and are refused in ``build/``
(``make test`` runs them in a temporary directory).  The kernels run headless with ``CISLUNAR_PROGRESS=plain``
(text progress bars on standard error, never widgets) over IPC sockets.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import functools
import importlib.metadata
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from cislunar.publish import provenance
from cislunar.publish.provenance import RunInfo
from cislunar.publish.report import REPORT_METADATA_KEY, STATUS_MEANINGS
from cislunar.utils import paths

__all__ = ["NotebookFailure", "NotebookResult", "discover", "resolve_build", "parameter_names", "parse_parameter",
           "run_notebook", "assemble_report", "run_all", "main"]

#: Per-cell time limit of a run, seconds, unless ``--timeout`` says otherwise (a hung cell ends with an error).
DEFAULT_TIMEOUT = {"full": 3600, "quick": 600}


class NotebookFailure(RuntimeError):
    """A notebook cell raised; the message names the notebook, the cell and the error."""


@dataclass(frozen=True)
class NotebookResult:
    """Outcome of one notebook run."""

    name: str
    seconds: float
    executed_path: Path
    report_markdown: str


def notebooks_dir() -> Path:
    """``notebooks/`` in the repository."""
    return paths.repo_root() / "notebooks"


def discover(selection=None) -> list[Path]:
    """Notebook sources ``notebooks/NN_*.py`` (or ``NNx_*.py``, e.g. ``09b``) in order, optionally filtered by name prefixes (``"01"``, ``"02_mut"``)."""
    found = sorted(p for p in notebooks_dir().glob("[0-9][0-9]*_*.py"))
    if not selection:
        return found
    chosen = []
    for key in selection:
        match = [p for p in found if p.stem.startswith(key) or p.name == key]
        if not match:
            raise ValueError(f"no notebook matches {key!r}; available: {[p.stem for p in found]}")
        chosen.extend(m for m in match if m not in chosen)
    return chosen


def _extract_report(nb) -> str:
    parts = []
    for cell in nb.cells:
        for out in cell.get("outputs", []):
            if out.get("metadata", {}).get(REPORT_METADATA_KEY):
                parts.append(out["data"]["text/markdown"])
    return "\n\n".join(parts)


def resolve_build(output_dir, *, quick: bool) -> Path:
    """The build directory of a run: ``output_dir`` if given, else ``build/`` (full) or ``build-quick/`` (quick).

    Raises
    ------
    ValueError
        If a quick run would write into the full build directory ``build/``.
    """
    if output_dir is None or str(output_dir) == "":
        return paths.quick_build_dir() if quick else paths.build_dir()
    build = paths.build_dir(output_dir)  # a path only: nothing is created until a notebook runs
    if quick and build.resolve() == (paths.repo_root() / "build").resolve():
        raise ValueError(f"output_dir: quick runs never write into the full build directory {build}; "
                         "omit it (build-quick/) or pick another directory")
    return build


def _parameter_path(build: Path) -> str:
    """``OUTPUT_DIR`` as passed to the notebook: relative to the repository when inside it (no machine paths)."""
    try:
        return str(build.resolve().relative_to(paths.repo_root().resolve()))
    except ValueError:
        return str(build)


@contextlib.contextmanager
def _headless_environment():
    """Environment inherited by the kernel: plain-text progress bars (unless switched off) for headless runs."""
    saved = {k: os.environ.get(k) for k in ("CISLUNAR_PROGRESS", "JUPYTER_PREFER_ENV_PATH")}
    if os.environ.get("CISLUNAR_PROGRESS", "").strip().lower() != "off":
        os.environ["CISLUNAR_PROGRESS"] = "plain"
    os.environ.setdefault("JUPYTER_PREFER_ENV_PATH", "1")
    try:
        yield
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


@functools.cache
def _headless_kernel_manager():
    """Kernel manager class whose shutdown sends no SIGINT.

    jupyter_client (8.x) interrupts a kernel with SIGINT to its whole process group before every shutdown, even a
    polite one after the last cell.  When the signal lands while the kernel is still finishing its last message
    handler, ipykernel logs "KeyboardInterrupt caught in kernel." to the runner's standard error (and any worker
    process the notebook left in its group sees a KeyboardInterrupt).  A finished headless run has nothing to
    interrupt: this manager skips the interrupt while shutting down and keeps the shutdown request (then SIGTERM,
    then SIGKILL after ``shutdown_wait_time`` if the kernel does not exit).
    """
    from jupyter_client import AsyncKernelManager

    class HeadlessKernelManager(AsyncKernelManager):
        async def _async_interrupt_kernel(self) -> None:
            if self.shutting_down:
                return
            await super()._async_interrupt_kernel()

    HeadlessKernelManager.__module__ = __name__
    HeadlessKernelManager.__qualname__ = "HeadlessKernelManager"
    return HeadlessKernelManager


@contextlib.contextmanager
def _kernel_config():
    """Kernel manager configuration: IPC sockets in a private temporary directory instead of unencrypted TCP, and
    a manager that shuts kernels down without SIGINT (:func:`_headless_kernel_manager`).

    Each run gets its own socket directory, so concurrent runs (two pytest workers, two terminals) never share
    socket names, and nothing is left in the build directory.  Under the command line the directory lies inside
    the child's private temporary folder (``TMPDIR``), which the parent removes even when it had to kill the child.
    """
    from traitlets.config import Config

    sockets = tempfile.mkdtemp(prefix="cislunar-kernel-" if len(tempfile.gettempdir()) < 40 else "k-")
    cfg = Config()
    cfg.KernelManager.transport = "ipc"
    cfg.KernelManager.ip = os.path.join(sockets, "kernel")
    cfg.NotebookClient.kernel_manager_class = _headless_kernel_manager()
    try:
        yield cfg
    finally:
        shutil.rmtree(sockets, ignore_errors=True)


def parameter_names(source: Path) -> dict:
    """``{name: default value source text}`` of the cell tagged ``parameters`` of a jupytext source.

    Raises
    ------
    NotebookFailure
        When the source has no cell, or more than one cell, tagged ``parameters``.
    """
    import jupytext

    nb = jupytext.read(source)
    cells = [c for c in nb.cells if "parameters" in c.metadata.get("tags", [])]
    if len(cells) != 1:
        raise NotebookFailure(f"{Path(source).stem}: needs exactly one cell tagged 'parameters'")
    out = {}
    for node in ast.parse(cells[0].source).body:
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                if isinstance(target, ast.Name):
                    out[target.id] = ast.get_source_segment(cells[0].source, node.value) if node.value else ""
    return out


def parse_parameter(text: str) -> tuple[str, object]:
    """``"NAME=VALUE"`` -> ``(NAME, value)``; the value is read as a Python literal (``24``, ``1e-3``, ``(3, 5)``,
    ``True``, ``'x'``), else kept as a string."""
    if not isinstance(text, str) or "=" not in text:
        raise ValueError(f"parameter must look like NAME=VALUE; got {text!r}")
    name, value = text.split("=", 1)
    name = name.strip()
    if not name.isidentifier():
        raise ValueError(f"parameter name must be an identifier; got {name!r}")
    try:
        return name, ast.literal_eval(value.strip())
    except (ValueError, SyntaxError):
        return name, value.strip()


def _check_parameters(source: Path, parameters: dict) -> None:
    known = parameter_names(source)
    unknown = sorted(set(parameters) - set(known))
    if unknown:
        raise ValueError(f"parameters: {Path(source).stem} has no parameter {', '.join(unknown)}; its parameters "
                         f"cell defines {', '.join(sorted(known))}")


def _set_aside_failed(build: Path, name: str) -> Path:
    """Move a failed run to ``<build>/notebooks/failed/`` and drop its stale report section.

    ``<build>/notebooks`` then holds only notebooks that ran to the end, which is what the report and the book show.
    """
    failed = build / "notebooks" / "failed"
    failed.mkdir(parents=True, exist_ok=True)
    target = failed / f"{name}.ipynb"
    executed = build / "notebooks" / f"{name}.ipynb"
    if executed.is_file():
        os.replace(executed, target)
    (build / "report" / f"{name}.md").unlink(missing_ok=True)
    return target


def _failing_cell(path: Path):
    """``(index, execution count, first line)`` of the cell a papermill run stopped in, from its saved notebook."""
    import nbformat

    if not path.is_file():
        return None, None, ""
    nb = nbformat.read(path, as_version=4)
    for i, cell in enumerate(nb.cells):
        status = cell.get("metadata", {}).get("papermill", {}).get("status")
        if status in ("running", "failed"):
            head = (cell.source.strip().splitlines() or [""])[0]
            return i, cell.get("execution_count"), head
    return None, None, ""


def _timed_out_cell(nb, message: str):
    """``(index in the executed notebook, first line)`` of the cell a timeout names in its message (nbclient gives
    a preview of the cell's source; papermill inserts its injected-parameters cell after the parameters cell)."""
    marker = "Here is a preview of the cell contents:"
    if marker not in message:
        return None, ""
    preview = message.split(marker, 1)[1].strip().strip("-").strip()
    try:
        lines = ast.literal_eval(preview.splitlines()[0].strip()) if preview.startswith("[") else preview.splitlines()
    except (ValueError, SyntaxError):
        lines = preview.splitlines()
    head = (lines[0] if lines else "").strip()
    params_at = next((i for i, c in enumerate(nb.cells) if "parameters" in c.metadata.get("tags", [])), -1)
    for i, cell in enumerate(nb.cells):
        if head and cell.source.strip().startswith(head):
            return i + (1 if i > params_at >= 0 else 0), head
    return None, head


def run_notebook(source: Path, *, quick: bool, seed: int = 0, output_dir=None, kernel: str = "python3",
                 parameters: dict | None = None, timeout: float | None = None, run: RunInfo | None = None,
                 log_output: bool = False) -> NotebookResult:
    """Convert ``source`` with jupytext, execute it with papermill and collect its report table.

    Parameters
    ----------
    source : Path
        ``notebooks/NN_topic.py``.
    quick : bool
        Passed as the ``QUICK`` parameter (smaller sizes, same science).
    seed : int
        Passed as ``SEED``.
    output_dir : path-like, optional
        Build directory, passed as ``OUTPUT_DIR`` (relative to the repository when inside it).  Default
        ``build/`` for full runs and ``build-quick/`` for quick ones; a quick run into ``build/`` is refused.
    kernel : str
        Jupyter kernel name.
    parameters : dict, optional
        Further parameters, each of which must be defined in the notebook's ``parameters`` cell.
    timeout : float, optional
        Per-cell time limit, s (default :data:`DEFAULT_TIMEOUT` of the mode).
    run : RunInfo, optional
        The run this execution belongs to (default: a new run of its own).
    log_output : bool
        Log the cells' output as they run (papermill's logger, at INFO level).

    Raises
    ------
    NotebookFailure
        When a cell raises or exceeds the time limit; the message names the notebook and the cell.
    ValueError
        When a quick run targets ``build/``, or a parameter is not one of the notebook's.
    """
    import jupytext
    import nbformat
    import papermill as pm

    build = resolve_build(output_dir, quick=quick)
    parameters = dict(parameters or {})
    for reserved in ("QUICK", "SEED", "OUTPUT_DIR"):
        if reserved in parameters:
            raise ValueError(f"parameters: {reserved} is set by the runner (use quick=, seed=, output_dir=)")
    _check_parameters(source, parameters)
    mode = "quick" if quick else "full"
    if run is None:
        run = provenance.new_run(quick=quick, seed=seed, root=paths.repo_root())
    if run.mode != mode:
        raise ValueError(f"run: a {run.mode}-mode run cannot execute a notebook in {mode} mode")
    if timeout is None:
        timeout = DEFAULT_TIMEOUT[mode]
    if not (isinstance(timeout, (int, float)) and timeout > 0):
        raise ValueError(f"timeout must be a positive number of seconds; got {timeout!r}")
    src_dir = build / "notebooks" / "_sources"
    src_dir.mkdir(parents=True, exist_ok=True)
    name = source.stem
    nb = jupytext.read(source)
    nb.metadata.setdefault("kernelspec", {"name": kernel, "display_name": "Python 3", "language": "python"})
    nb.metadata.setdefault("language_info", {"name": "python"})
    ipynb = src_dir / f"{name}.ipynb"
    nbformat.write(nb, ipynb)
    executed = build / "notebooks" / f"{name}.ipynb"
    params = {"QUICK": bool(quick), "SEED": int(seed), "OUTPUT_DIR": _parameter_path(build)}
    params.update(parameters)
    start = time.perf_counter()
    try:
        with _headless_environment(), _kernel_config() as config:
            pm.execute_notebook(str(ipynb), str(executed), parameters=params, kernel_name=kernel,
                                cwd=str(build / "notebooks"), progress_bar=False, log_output=log_output,
                                config=config, execution_timeout=timeout)
    except Exception as exc:  # noqa: BLE001 - every failure is reported with its notebook and cell
        seconds = time.perf_counter() - start
        index, count, head = _failing_cell(executed)
        if isinstance(exc, pm.PapermillExecutionError):
            index, count = exc.cell_index, exc.exec_count
            what = f"raised {exc.ename}: {exc.evalue}"
        elif type(exc).__name__ == "CellTimeoutError":
            what = f"exceeded the per-cell time limit of {timeout:g} s"
            index, head = _timed_out_cell(nb, str(exc))
        else:
            what = f"raised {type(exc).__name__}: {exc}"
        if isinstance(exc, pm.PapermillExecutionError) and executed.is_file():
            cells = nbformat.read(executed, as_version=4).cells
            head = (cells[index].source.strip().splitlines() or [""])[0] if index < len(cells) else ""
        kept = _set_aside_failed(build, name)
        message = f"{name}: cell {index} (execution count {count}, starting {head!r}) {what}"
        provenance.write_record(build, name, run, status="failed", seconds=seconds, error=message)
        assemble_report(build)
        raise NotebookFailure(f"{message} (partly executed notebook: {kept})") from None
    seconds = time.perf_counter() - start
    done = nbformat.read(executed, as_version=4)
    report = _extract_report(done)
    if not report:
        _set_aside_failed(build, name)
        provenance.write_record(build, name, run, status="failed", seconds=seconds, error="no closing table")
        assemble_report(build)
        raise NotebookFailure(f"{name}: no paper-vs-reproduction table was displayed (ComparisonTable.display())")
    done.metadata[provenance.METADATA_KEY] = dict(asdict(run), notebook=name, seconds=round(seconds, 1))
    nbformat.write(done, executed)
    (build / "notebooks" / "failed" / f"{name}.ipynb").unlink(missing_ok=True)
    rep_dir = build / "report"
    rep_dir.mkdir(parents=True, exist_ok=True)
    (rep_dir / f"{name}.md").write_text(f"## {name}\n\n{provenance.provenance_line(run, seconds)}\n\n{report}\n")
    provenance.write_record(build, name, run, status="ok", seconds=seconds)
    assemble_report(build)
    return NotebookResult(name, seconds, executed, report)


def assemble_report(output_dir=None, *, expected=None) -> Path:
    """Concatenate ``<build>/report/*.md`` into ``<build>/report.md``, stating where the sections come from.

    The header says the mode when every section comes from one run of one mode, names the runs of a mixed build,
    and lists every notebook of ``expected`` (default: none) that is missing or failed, so a partial build never
    reads as complete.
    """
    build = paths.build_dir(output_dir)
    parts = sorted((build / "report").glob("*.md"))
    bodies = [p.read_text() for p in parts]
    provs = [provenance.parse_provenance_line(b) or {} for b in bodies]
    modes = sorted({p.get("mode") for p in provs if p.get("mode")})
    runs = sorted({p.get("run_id") for p in provs if p.get("run_id")})
    records = provenance.read_records(build)
    names = [p.stem for p in parts]
    missing = [n for n in (expected or []) if n not in names]
    failed = sorted(n for n, r in records.items() if r.get("status") != "ok")
    lines = []
    if missing or failed:
        lines.append(f"**Incomplete build.** {len(names)} section(s) present; "
                     + (f"missing: {', '.join(missing)}; " if missing else "")
                     + (f"failed or interrupted: {', '.join(failed)}; " if failed else "")
                     + "the book refuses this build.")
    if len(runs) > 1:
        lines.append(f"**Mixed runs.** Sections come from {len(runs)} runs ({', '.join(runs)}); each section says "
                     "which.")
    if modes == ["full"]:
        lines.append("**Mode: full.** Every section below comes from a full-fidelity run (`make reproduce`).")
    elif modes == ["quick"]:
        lines.append("**Mode: quick.** Every section below comes from a quick run (reduced sizes, same science); "
                     "the paper-scale numbers come from `make reproduce`.")
    elif modes:
        lines.append("**Mode: mixed.** Sections come from full and quick runs; each section says which.")
    else:
        lines.append("No notebook has run into this directory yet.")
    if len(runs) == 1:
        p = next(p for p in provs if p.get("run_id"))
        lines.append(f"Run {p['run_id']}, commit {p.get('commit', 'unknown')}.")
    text = ["# Paper versus reproduction", "", "\n\n".join(lines), "",
            "Generated by `python -m cislunar.publish.notebooks`; one section per executed notebook. Status words: "
            + "; ".join(f"*{w}*: {m}" for w, m in STATUS_MEANINGS.items()) + ".", ""]
    text += bodies
    out = build / "report.md"
    tmp = out.with_name(f".report.md.{os.getpid()}")
    tmp.write_text("\n".join(text))
    os.replace(tmp, out)  # atomic: concurrent runs into one build directory never leave a half-written report
    return out
# ---------------------------------------------------------------------------------------------------------------
# The command line: children in their own sessions, two at a time, a staging folder, Ctrl-C that ends everything
# ---------------------------------------------------------------------------------------------------------------
#: Quick/full seconds assumed for a notebook never run into this build (used for order and the estimate only).
_DEFAULT_SECONDS = {"quick": 20.0, "full": 60.0}


def _workers_asked(source: Path, parameters: dict, quick: bool = False) -> int:
    """Processes a notebook asks for: its ``WORKERS`` parameter as given, else its default; a default of ``None``
    ("QUICK picks") counts as 1 in quick mode and 2 in full mode; 1 for a notebook without the parameter."""
    value = parameters.get("WORKERS")
    if value is None:
        names = parameter_names(source)
        if "WORKERS" not in names:
            return 1
        try:
            value = ast.literal_eval(names["WORKERS"])
        except (ValueError, SyntaxError):
            return 2  # an expression (e.g. from os.cpu_count()): assume it wants the machine
        if value is None:
            return 1 if quick else 2
    return int(value) if isinstance(value, int) and not isinstance(value, bool) else 1


def _kill_tree(pid: int, grace: float = 2.0) -> None:
    """End a process and every descendant (kernels live in sessions of their own; pool workers under them)."""
    import psutil

    try:
        root = psutil.Process(pid)
    except psutil.NoSuchProcess:
        return
    procs = []
    for _ in range(3):  # stop first, so nothing forks a new child between the listing and the kill
        found = [root, *root.children(recursive=True)] if root.is_running() else []
        for proc in found:
            if proc not in procs:
                procs.append(proc)
                with contextlib.suppress(psutil.Error):
                    proc.suspend()
    for proc in procs:
        with contextlib.suppress(psutil.Error):
            proc.terminate()
            proc.resume()
    _, alive = psutil.wait_procs(procs, timeout=grace)
    for proc in alive:
        with contextlib.suppress(psutil.Error):
            proc.kill()
    psutil.wait_procs(alive, timeout=grace)


@dataclass
class _Child:
    source: Path
    proc: subprocess.Popen
    tmp: Path
    log: Path
    result: Path
    started: float
    expected: float | None  # seconds of the last run of the same mode into this build; None: never run there
    workers: int
    offset: int = 0


def _stream_new_lines(child: _Child, say) -> None:
    """Print what a child wrote to its log since the last call, each line prefixed with its notebook."""
    try:
        with open(child.log, "rb") as f:
            f.seek(child.offset)
            chunk = f.read()
    except OSError:
        return
    end = chunk.rfind(b"\n") + 1
    child.offset += end
    for line in chunk[:end].decode("utf-8", "replace").replace("\r", "\n").splitlines():
        if line.strip():
            say(f"[{child.source.stem}] {line}")


def _last_line(path: Path, limit: int = 100) -> str:
    """The last non-blank line of a log file (progress bars rewrite their line with carriage returns)."""
    try:
        with open(path, "rb") as f:
            f.seek(0, os.SEEK_END)
            f.seek(max(0, f.tell() - 4096))
            tail = f.read().decode("utf-8", "replace")
    except OSError:
        return ""
    lines = [ln.strip() for ln in tail.replace("\r", "\n").splitlines() if ln.strip()]
    if not lines:
        return ""
    line = lines[-1]
    if " - papermill - INFO - " in line:
        line = line.split(" - papermill - INFO - ", 1)[1]
    return line[:limit]


class _Interrupted(Exception):
    pass


def _run_order(sources, last_seconds: dict, parameters: dict, quick: bool) -> list:
    """The order the runner starts notebooks in: longest expected run first.

    A notebook's expected run is its time in the last run of this mode into this build (``last_seconds``, name
    -> seconds or None); without one, :data:`_DEFAULT_SECONDS` times the processes it asks for
    (:func:`_workers_asked`), so that on a fresh clone the notebooks that take the whole machine come first, back
    to back, and the one-process notebooks pair up after them (in the alphabetical order a fresh clone used to
    start everything in, a whole-machine notebook reached the head of the queue while a one-process notebook ran,
    and waited for it with a core idle).  Ties keep the order of ``sources``.
    """
    mode = "quick" if quick else "full"

    def expected(src):
        last = last_seconds.get(src.stem)
        return _DEFAULT_SECONDS[mode] * _workers_asked(src, parameters, quick) if last is None else float(last)

    return sorted(sources, key=lambda s: -expected(s))


def run_all(sources, *, quick: bool, seed: int = 0, output_dir=None, parameters: dict | None = None,
            timeout: float | None = None, jobs: int = 2, log_output: bool = False, heartbeat: float = 15.0,
            out=None) -> int:
    """Run notebooks as the command line does; returns the exit status (0 all ok, 1 a failure, 130 interrupted).

    Each notebook runs in a child process started in a session of its own, at most ``jobs`` at a time; a
    notebook whose ``WORKERS`` parameter asks for several processes runs alone.  Output goes to a staging folder
    that replaces the build only when every notebook succeeded; otherwise the build is untouched and the staging
    folder becomes ``<build>-incomplete``.  SIGINT and SIGTERM end every process the run started and remove their
    temporary folders.

    Parameters
    ----------
    sources : list of Path
        Notebook sources (:func:`discover`).
    quick, seed, output_dir, parameters, timeout, log_output
        As in :func:`run_notebook`; ``parameters`` apply to every notebook that defines them (each must be
        defined by at least one of ``sources``).
    jobs : int
        Notebooks run side by side (>= 1).
    heartbeat : float
        Seconds between status lines of the running notebooks.
    out : file, optional
        Where status lines go (default standard output).
    """
    out = out or sys.stdout
    parameters = dict(parameters or {})
    if not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs must be a positive int; got {jobs!r}")
    known = {s.stem: parameter_names(s) for s in sources}
    unknown = sorted(n for n in parameters if not any(n in k for k in known.values()))
    if unknown:
        raise ValueError(f"parameters: no selected notebook defines {', '.join(unknown)}")
    target = resolve_build(output_dir, quick=quick)
    root = paths.repo_root()
    run = provenance.new_run(quick=quick, seed=seed, root=root)
    mode = run.mode
    previous = provenance.read_records(target)
    stage = target.with_name(f"{target.name}.staging-{run.run_id}")
    selected = {s.stem for s in sources}
    if target.is_dir() and (target / "runs").is_dir() and selected != {s.stem for s in discover()}:
        # a selection: the stage starts from the current build, less what this run makes again
        shutil.copytree(target, stage, ignore=shutil.ignore_patterns("book", ".book", "logs"))
        for name in selected:
            for stale in (stage / "notebooks" / f"{name}.ipynb", stage / "report" / f"{name}.md",
                          stage / "runs" / f"{name}.json", stage / "notebooks" / "failed" / f"{name}.ipynb"):
                stale.unlink(missing_ok=True)
    stage.mkdir(parents=True, exist_ok=True)
    (stage / "logs").mkdir(exist_ok=True)

    def last_seconds(name):
        """This notebook's time in the last run of the same mode into this build, or None."""
        rec = previous.get(name)
        return float(rec["seconds"]) if rec and rec.get("mode") == mode else None

    queue = _run_order(sources, {s.stem: last_seconds(s.stem) for s in sources}, parameters, quick)
    running: list[_Child] = []
    outcome: dict = {}
    stop = {"signal": None}

    def on_signal(signum, frame):
        stop["signal"] = signum
        raise _Interrupted()

    saved = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}

    def say(text):
        print(text, file=out, flush=True)

    def start(src):
        # a short private folder: the kernel's IPC socket paths must stay under the 107-byte limit of AF_UNIX
        base = tempfile.gettempdir()
        if len(base) > 40 and os.access("/tmp", os.W_OK):
            base = "/tmp"
        tmp = Path(tempfile.mkdtemp(prefix="cl-", dir=base))
        spec = {"source": str(src), "quick": quick, "seed": seed, "output_dir": str(stage),
                "parameters": {k: v for k, v in parameters.items() if k in known[src.stem]},
                "timeout": timeout, "run": asdict(run), "result": str(tmp / "result.json"),
                "log_output": True}
        (tmp / "spec.json").write_text(json.dumps(spec))
        log = stage / "logs" / f"{src.stem}.log"
        env = dict(os.environ, TMPDIR=str(tmp), JUPYTER_RUNTIME_DIR=str(tmp / "runtime"), PYTHONUNBUFFERED="1")
        with open(log, "w") as f:
            proc = subprocess.Popen([sys.executable, "-m", "cislunar.publish.notebooks", "--child",
                                     str(tmp / "spec.json")], stdout=f, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                    env=env, start_new_session=True, cwd=str(root))
        w = _workers_asked(src, parameters, quick)
        running.append(_Child(src, proc, tmp, log, tmp / "result.json", time.monotonic(),
                              last_seconds(src.stem), w))
        last = last_seconds(src.stem)
        est = "" if last is None else f", last run {last:.0f} s"
        say(f"[{src.stem}] running ({mode}{est}; {w} process{'es' if w > 1 else ''}; log {log})")

    def finish(child):
        running.remove(child)
        seconds = time.monotonic() - child.started
        data = json.loads(child.result.read_text()) if child.result.is_file() else None
        shutil.rmtree(child.tmp, ignore_errors=True)
        if data and data.get("ok"):
            outcome[child.source.stem] = "ok"
            say(f"[{child.source.stem}] done in {seconds:.1f} s")
        else:
            outcome[child.source.stem] = "failed"
            err = data.get("error") if data else f"the child process exited with status {child.proc.returncode}"
            if not data:
                provenance.write_record(stage, child.source.stem, run, status="failed", seconds=seconds,
                                        error=err)
            say(f"[{child.source.stem}] FAILED after {seconds:.1f} s: {err} (log {child.log})")

    total = time.monotonic()
    last_beat = time.monotonic()
    try:
        while queue or running:
            for child in [c for c in running if c.proc.poll() is not None]:
                finish(child)
            exclusive_running = any(c.workers > 1 for c in running)
            while queue and not exclusive_running and len(running) < jobs:
                head = queue[0]
                if _workers_asked(head, parameters, quick) > 1:
                    if running:
                        break  # wait until the machine is free for it
                    start(queue.pop(0))
                    break
                start(queue.pop(0))
                exclusive_running = any(c.workers > 1 for c in running)
            if heartbeat and time.monotonic() - last_beat >= heartbeat and running:
                last_beat = time.monotonic()
                for c in running:
                    el = time.monotonic() - c.started
                    of = "" if c.expected is None else f" of ~{c.expected:.0f} s (last run)"
                    say(f"[{c.source.stem}] {el:.0f} s{of}: {_last_line(c.log)}")
            if log_output:
                for c in running:
                    _stream_new_lines(c, say)
            time.sleep(0.2)
    except _Interrupted:
        name = signal.Signals(stop["signal"]).name
        say(f"{name}: stopping {len(running)} running notebook(s) and their processes...")
        for c in list(running):
            _kill_tree(c.proc.pid)
            provenance.write_record(stage, c.source.stem, run, status="interrupted",
                                    seconds=time.monotonic() - c.started, error=f"stopped by {name}")
            outcome[c.source.stem] = "interrupted"
            shutil.rmtree(c.tmp, ignore_errors=True)
            running.remove(c)
    finally:
        for s, handler in saved.items():
            signal.signal(s, handler)
    every = {s.stem for s in discover()}
    expected = sorted(every if selected == every else selected | set(provenance.read_records(stage)))
    assemble_report(stage, expected=expected)
    bad = sorted(n for n in selected if outcome.get(n) != "ok")
    seconds = time.monotonic() - total
    if not bad and stop["signal"] is None:
        old = target.with_name(f".{target.name}.old-{run.run_id}")
        if target.exists():
            os.rename(target, old)
        os.rename(stage, target)
        shutil.rmtree(old, ignore_errors=True)
        say(f"report: {target / 'report.md'}; run {run.run_id}; total {seconds:.1f} s; 0 failed")
        return 0
    incomplete = target.with_name(f"{target.name}-incomplete")
    shutil.rmtree(incomplete, ignore_errors=True)
    os.rename(stage, incomplete)
    states = ", ".join(f"{n}: {outcome.get(n, 'not started')}" for n in bad)
    say(f"incomplete run {run.run_id} ({states}); "
        f"{target} left as it was; what ran is in {incomplete}; total {seconds:.1f} s")
    return 130 if stop["signal"] is not None else 1


def _skip_iri_grammar() -> None:
    """Mark the package ``rfc3987_syntax`` absent in this process unless it is already loaded.

    jsonschema imports it, when installed, for its optional ``iri`` format checker, and it compiles a grammar at
    import: 0.8-2 s of the 1.4-2.5 s that importing papermill and jupytext takes (Jupyter's
    ``jsonschema[format-nongpl]`` pulls it in).  Notebook validation never checks that format, and jsonschema skips
    the checker when the import fails, so the runner (which reads every notebook's ``parameters`` cell with
    jupytext) and each of its children (one per notebook) start that much sooner.  Called only from the command
    line's process (:func:`main`), never on import.
    """
    sys.modules.setdefault("rfc3987_syntax", None)


def _child(spec_path: str) -> int:
    """Run one notebook as the command line's child process (``--child SPEC``, which :func:`main` hands here after
    :func:`_skip_iri_grammar`); writes the result JSON."""
    import logging

    spec = json.loads(Path(spec_path).read_text())
    logging.basicConfig(level=logging.INFO if spec.get("log_output") else logging.WARNING, stream=sys.stdout,
                        format="%(message)s")
    os.makedirs(os.environ.get("JUPYTER_RUNTIME_DIR", tempfile.gettempdir()), exist_ok=True)
    result = {"ok": False}
    try:
        res = run_notebook(Path(spec["source"]), quick=spec["quick"], seed=spec["seed"],
                           output_dir=spec["output_dir"], parameters=spec["parameters"], timeout=spec["timeout"],
                           run=RunInfo(**spec["run"]), log_output=spec.get("log_output", False))
        result = {"ok": True, "seconds": res.seconds}
    except (NotebookFailure, ValueError) as exc:
        result = {"ok": False, "error": str(exc)}
    Path(spec["result"]).write_text(json.dumps(result))
    return 0 if result["ok"] else 1


#: Labels of ``[project.urls]`` in ``pyproject.toml`` that name where the repository can be cloned from.
_REPOSITORY_LABELS = ("repository", "source", "source code", "code", "homepage")


def _repository_url() -> str | None:
    """The repository URL declared in the installed package's metadata (``[project.urls]``), if any."""
    try:
        entries = importlib.metadata.metadata("cislunar").get_all("Project-URL") or []
    except importlib.metadata.PackageNotFoundError:
        return None
    for entry in entries:
        label, _, url = entry.partition(",")
        if label.strip().lower() in _REPOSITORY_LABELS and url.strip():
            return url.strip()
    return None


def _missing_checkout(folder: str, command: str) -> str | None:
    """``None`` if the repository's ``folder`` is reachable, else the one-line error that ``command`` prints.

    The notebooks, the book's configuration and the build folders live in the repository, not in the installed
    package: an installed wheel finds them only through ``CISLUNAR_ROOT``.
    """
    try:
        root = paths.repo_root()
    except FileNotFoundError:
        where = "the installed package is not inside a checkout of the repository and CISLUNAR_ROOT is not set"
    else:
        if (root / folder).is_dir():
            return None
        where = f"{root} has no {folder}/ folder"
    url = _repository_url()
    clone = f"git clone {url}" if url else "clone the cislunar repository"
    return (f"error: {command} needs the repository's {folder}/ folder, which the installed package does not "
            f"include ({where}); {clone} and run it from that checkout, or set CISLUNAR_ROOT to a checkout")


def main(argv=None) -> int:
    """Command-line entry point; returns the process exit status (2 on bad arguments or outside a checkout)."""
    parser = argparse.ArgumentParser(prog="python -m cislunar.publish.notebooks", description=__doc__.split("\n\n")[0])
    parser.add_argument("names", nargs="*", help="notebook number or name prefixes (default: all)")
    parser.add_argument("--quick", action="store_true", help="quick mode: smaller sizes, same science")
    parser.add_argument("--seed", type=int, default=0, help="random seed passed to every notebook")
    parser.add_argument("--output-dir", default=None,
                        help="build directory (default: <repo>/build, or <repo>/build-quick with --quick)")
    parser.add_argument("-p", "--parameter", action="append", default=[], metavar="NAME=VALUE",
                        help="set a notebook parameter (a Python literal, e.g. -p N_NODES=24); repeatable")
    parser.add_argument("--timeout", type=float, default=None,
                        help="per-cell time limit in seconds (default 3600 full, 600 quick)")
    parser.add_argument("--jobs", type=int, default=2, help="notebooks run side by side (default 2)")
    parser.add_argument("--log-output", action="store_true",
                        help="also print every cell's output as it runs (it is always in <build>/logs/)")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    _skip_iri_grammar()  # this process reads every notebook's parameters cell with jupytext: 2 s sooner
    if args.child:
        return _child(args.child)
    missing = _missing_checkout("notebooks", "cislunar-notebooks")
    if missing:
        print(missing, file=sys.stderr)
        return 2
    try:
        sources = discover(args.names)
        params = dict(parse_parameter(p) for p in args.parameter)
        resolve_build(args.output_dir, quick=args.quick)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        return run_all(sources, quick=args.quick, seed=args.seed, output_dir=args.output_dir, parameters=params,
                       timeout=args.timeout, jobs=args.jobs, log_output=args.log_output)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())

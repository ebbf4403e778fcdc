"""Execute the literate notebooks headless and gather their paper-vs-reproduction tables.

Usage::

    python -m cislunar.publish.notebooks                 # every notebook at full fidelity into build/ (make reproduce)
    python -m cislunar.publish.notebooks --quick         # every notebook in quick mode into build-quick/
    python -m cislunar.publish.notebooks --quick 01 02   # a selection, by number or name prefix

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
import contextlib
import functools
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from cislunar.publish.report import REPORT_METADATA_KEY, STATUS_MEANINGS
from cislunar.utils import paths

__all__ = ["NotebookFailure", "NotebookResult", "discover", "resolve_build", "run_notebook", "assemble_report",
           "main"]


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
    build = paths.build_dir(output_dir)
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
    socket names, and nothing is left in the build directory.
    """
    import shutil
    import tempfile

    from traitlets.config import Config

    sockets = tempfile.mkdtemp(prefix="cislunar-kernel-")
    cfg = Config()
    cfg.KernelManager.transport = "ipc"
    cfg.KernelManager.ip = os.path.join(sockets, "kernel")
    cfg.NotebookClient.kernel_manager_class = _headless_kernel_manager()
    try:
        yield cfg
    finally:
        shutil.rmtree(sockets, ignore_errors=True)


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
    assemble_report(build)
    return target


def run_notebook(source: Path, *, quick: bool, seed: int = 0, output_dir=None, kernel: str = "python3",
                 extra_parameters: dict | None = None) -> NotebookResult:
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
    extra_parameters : dict, optional
        Further papermill parameters.

    Raises
    ------
    NotebookFailure
        When a cell raises; the message names the notebook and the cell.
    ValueError
        When a quick run targets ``build/``.
    """
    import jupytext
    import nbformat
    import papermill as pm

    build = resolve_build(output_dir, quick=quick)
    src_dir = build / "notebooks" / "_sources"
    src_dir.mkdir(parents=True, exist_ok=True)
    name = source.stem
    nb = jupytext.read(source)
    tags = [c.metadata.get("tags", []) for c in nb.cells]
    if sum("parameters" in t for t in tags) != 1:
        raise NotebookFailure(f"{name}: needs exactly one cell tagged 'parameters'")
    nb.metadata.setdefault("kernelspec", {"name": kernel, "display_name": "Python 3", "language": "python"})
    nb.metadata.setdefault("language_info", {"name": "python"})
    ipynb = src_dir / f"{name}.ipynb"
    nbformat.write(nb, ipynb)
    executed = build / "notebooks" / f"{name}.ipynb"
    params = {"QUICK": bool(quick), "SEED": int(seed), "OUTPUT_DIR": _parameter_path(build)}
    params.update(extra_parameters or {})
    start = time.perf_counter()
    try:
        with _headless_environment(), _kernel_config() as config:
            pm.execute_notebook(str(ipynb), str(executed), parameters=params, kernel_name=kernel,
                                cwd=str(build / "notebooks"), progress_bar=False, log_output=False,
                                config=config)
    except pm.PapermillExecutionError as exc:
        done = nbformat.read(executed, as_version=4)
        cell = done.cells[exc.cell_index] if exc.cell_index < len(done.cells) else None
        head = (cell.source.strip().splitlines() or [""])[0] if cell is not None else ""
        kept = _set_aside_failed(build, name)
        raise NotebookFailure(
            f"{name}: cell {exc.cell_index} (execution count {exc.exec_count}, starting {head!r}) raised "
            f"{exc.ename}: {exc.evalue} (partly executed notebook: {kept})"
        ) from None
    seconds = time.perf_counter() - start
    done = nbformat.read(executed, as_version=4)
    report = _extract_report(done)
    if not report:
        _set_aside_failed(build, name)
        raise NotebookFailure(f"{name}: no paper-vs-reproduction table was displayed (ComparisonTable.display())")
    (build / "notebooks" / "failed" / f"{name}.ipynb").unlink(missing_ok=True)
    rep_dir = build / "report"
    rep_dir.mkdir(parents=True, exist_ok=True)
    mode = "quick" if quick else "full"
    (rep_dir / f"{name}.md").write_text(f"## {name} ({mode} mode, {seconds:.0f} s)\n\n{report}\n")
    assemble_report(build)
    return NotebookResult(name, seconds, executed, report)


def assemble_report(output_dir=None) -> Path:
    """Concatenate ``<build>/report/*.md`` into ``<build>/report.md``, stating the mode(s) the sections ran in."""
    build = paths.build_dir(output_dir)
    parts = sorted((build / "report").glob("*.md"))
    bodies = [p.read_text() for p in parts]
    modes = sorted({m for b in bodies for m in ("full", "quick") if f" ({m} mode," in b.split("\n", 1)[0]})
    if modes == ["full"]:
        mode_line = "**Mode: full.** Every section below comes from a full-fidelity run (`make reproduce`)."
    elif modes == ["quick"]:
        mode_line = ("**Mode: quick.** Every section below comes from a quick run (reduced sizes, same science); "
                     "the paper-scale numbers come from `make reproduce`.")
    elif modes:
        mode_line = "**Mode: mixed.** Sections come from full and quick runs; each heading says which."
    else:
        mode_line = "No notebook has run into this directory yet."
    text = ["# Paper versus reproduction", "", mode_line, "",
            "Generated by `python -m cislunar.publish.notebooks`; one section per executed notebook. Status words: "
            + "; ".join(f"*{w}*: {m}" for w, m in STATUS_MEANINGS.items()) + ".", ""]
    text += bodies
    out = build / "report.md"
    tmp = out.with_name(f".report.md.{os.getpid()}")
    tmp.write_text("\n".join(text))
    os.replace(tmp, out)  # atomic: concurrent runs into one build directory never leave a half-written report
    return out


def main(argv=None) -> int:
    """Command-line entry point; returns the process exit status."""
    parser = argparse.ArgumentParser(prog="python -m cislunar.publish.notebooks", description=__doc__.split("\n\n")[0])
    parser.add_argument("names", nargs="*", help="notebook number or name prefixes (default: all)")
    parser.add_argument("--quick", action="store_true", help="quick mode: smaller sizes, same science")
    parser.add_argument("--seed", type=int, default=0, help="random seed passed to every notebook")
    parser.add_argument("--output-dir", default=None,
                        help="build directory (default: <repo>/build, or <repo>/build-quick with --quick)")
    args = parser.parse_args(argv)
    try:
        sources = discover(args.names)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        build = resolve_build(args.output_dir, quick=args.quick)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    failures = 0
    total = time.perf_counter()
    for src in sources:
        print(f"[{src.stem}] running ({'quick' if args.quick else 'full'})...", flush=True)
        try:
            res = run_notebook(src, quick=args.quick, seed=args.seed, output_dir=build)
        except NotebookFailure as exc:
            failures += 1
            print(f"[{src.stem}] FAILED: {exc}", file=sys.stderr, flush=True)
            continue
        print(f"[{src.stem}] done in {res.seconds:.1f} s -> {res.executed_path}", flush=True)
    report = assemble_report(build)
    print(f"report: {report}; total {time.perf_counter() - total:.1f} s; {failures} failed", flush=True)
    return 1 if failures else 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())

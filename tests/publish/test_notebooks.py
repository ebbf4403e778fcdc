"""Every notebook runs end to end in quick mode through the same runner as ``make reproduce``.

The runs go to the session's temporary directory (``quick_runs`` in conftest.py), never to ``build/``, and each
notebook runs once per session: the book tests (tests/test_book.py) render the same executed notebooks.
"""

import os
import re

import nbformat
import pytest
from conftest import selected_notebooks

from cislunar.publish import notebooks
from cislunar.utils import paths

SOURCES = selected_notebooks()


@pytest.mark.notebook
@pytest.mark.parametrize("source", SOURCES, ids=[p.stem for p in SOURCES])
def test_notebook_quick(source, quick_runs):
    result = quick_runs.get(source)
    assert result["ok"], result.get("error")
    report = result["report"]
    assert report.count("|") > 10, "closing paper-vs-reproduction table is empty"
    assert "| quantity | paper | reproduced | status |" in report
    rows = [ln for ln in report.splitlines() if ln.startswith("| ") and "quantity" not in ln]
    for row in rows:
        cells = [c.strip().lower() for c in row.strip("|").split(" | ")]
        assert "nan" not in cells[:3], f"{source.stem}: NaN in a table row: {row}"
        assert "failed" not in cells[3], f"{source.stem}: a check failed: {row}"
    executed = quick_runs.build / "notebooks" / f"{source.stem}.ipynb"
    assert executed.is_file()
    warned = printed_warnings(executed)
    assert not warned, f"{source.stem}: cells print warnings (they reach the book): {warned}"
    assert (paths.repo_root() / "build").resolve() not in executed.resolve().parents


WARNING = re.compile(r"\b\w*Warning: ")


def printed_warnings(path):
    """``[(cell index, first line of the warning), ...]`` of an executed notebook's outputs."""
    out = []
    for i, cell in enumerate(nbformat.read(path, as_version=4).cells):
        for o in cell.get("outputs", []):
            text = o.get("text", "") if o.get("output_type") == "stream" else ""
            for line in text.splitlines():
                if WARNING.search(line):
                    out.append((i, line.strip()[:160]))
    return out


def test_printed_warnings_are_found(tmp_path):
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell("1"), nbformat.v4.new_code_cell("2")]
    nb.cells[0].outputs = [nbformat.v4.new_output("stream", name="stderr", text="progress: 100%|####| 3/3\n")]
    nb.cells[1].outputs = [nbformat.v4.new_output(
        "stream", name="stderr", text="/x/y.py:471: RuntimeWarning: divide by zero encountered in log\n  return\n")]
    path = tmp_path / "w.ipynb"
    nbformat.write(nb, path)
    assert printed_warnings(path) == [(1, "/x/y.py:471: RuntimeWarning: divide by zero encountered in log")]


def test_quick_runs_never_write_into_build(tmp_path):
    full = paths.repo_root() / "build"
    with pytest.raises(ValueError, match="output_dir"):
        notebooks.resolve_build(full, quick=True)
    with pytest.raises(ValueError, match="output_dir"):
        notebooks.resolve_build("build", quick=True)
    assert notebooks.resolve_build(None, quick=True) == paths.repo_root() / "build-quick"
    assert notebooks.resolve_build(None, quick=False) == full
    assert notebooks.resolve_build(tmp_path / "b", quick=True) == tmp_path / "b"
    assert notebooks.main(["--quick", "--output-dir", str(full), "01"]) == 2


def test_report_says_which_mode_and_run_made_it(tmp_path):
    from cislunar.publish import provenance

    full = provenance.new_run(quick=False, seed=0, root=paths.repo_root())
    quick = provenance.new_run(quick=True, seed=0, root=paths.repo_root())
    rep = tmp_path / "report"
    rep.mkdir()
    table = "| quantity | paper | reproduced | status |\n"
    (rep / "01_a.md").write_text(f"## 01_a\n\n{provenance.provenance_line(full, 3)}\n\n{table}")
    text = notebooks.assemble_report(tmp_path).read_text()
    assert "**Mode: full.**" in text and f"Run {full.run_id}, commit {full.commit}" in text
    assert "Incomplete" not in text and "Mixed" not in text
    (rep / "02_b.md").write_text(f"## 02_b\n\n{provenance.provenance_line(quick, 1)}\n\n{table}")
    text = notebooks.assemble_report(tmp_path).read_text()
    assert "**Mode: mixed.**" in text and "**Mixed runs.**" in text and full.run_id in text and quick.run_id in text
    (rep / "01_a.md").unlink()
    text = notebooks.assemble_report(tmp_path, expected=["01_a", "02_b"]).read_text()
    assert "**Mode: quick.**" in text and "**Incomplete build.**" in text and "missing: 01_a" in text


def test_headless_kernel_environment(monkeypatch):
    """Kernels run with plain-text progress bars (never widgets) unless bars are switched off, then restored."""
    import os

    monkeypatch.setenv("CISLUNAR_PROGRESS", "auto")
    with notebooks._headless_environment():
        assert os.environ["CISLUNAR_PROGRESS"] == "plain"
    assert os.environ["CISLUNAR_PROGRESS"] == "auto"
    monkeypatch.setenv("CISLUNAR_PROGRESS", "off")
    with notebooks._headless_environment():
        assert os.environ["CISLUNAR_PROGRESS"] == "off"
    monkeypatch.delenv("CISLUNAR_PROGRESS")
    with notebooks._headless_environment():
        assert os.environ["CISLUNAR_PROGRESS"] == "plain"
    assert "CISLUNAR_PROGRESS" not in os.environ


def test_runner_kernel_uses_private_ipc_sockets():
    with notebooks._kernel_config() as cfg:
        assert cfg.KernelManager.transport == "ipc"
        sockets = os.path.dirname(cfg.KernelManager.ip)
        assert os.path.isdir(sockets)
    assert not os.path.exists(sockets)



def test_runner_shuts_kernels_down_without_sigint(tmp_path):
    """Shutting the kernel down after the last cell sends no SIGINT to its process group.

    jupyter_client interrupts before every shutdown; when the SIGINT lands inside the kernel's last message handler
    ipykernel prints "KeyboardInterrupt caught in kernel." on the runner's stderr.  A child process the notebook
    leaves in the kernel's process group records any SIGINT it receives in a file.
    """
    import time

    import jupyter_client

    assert issubclass(notebooks._headless_kernel_manager(), jupyter_client.AsyncKernelManager)
    with notebooks._kernel_config() as cfg:
        assert cfg.NotebookClient.kernel_manager_class is notebooks._headless_kernel_manager()
    marker = tmp_path / "sigint.txt"
    ready = tmp_path / "ready.txt"
    child = (f"import signal, sys, time, pathlib\n"
             f"signal.signal(signal.SIGINT, lambda *a: (pathlib.Path({str(marker)!r}).write_text('SIGINT'), "
             f"sys.exit(0)))\n"
             f"pathlib.Path({str(ready)!r}).write_text('ready')\n"
             f"time.sleep(8)\n")
    src = tmp_path / "97_child.py"
    src.write_text(
        '# %% tags=["parameters"]\nQUICK = False\nSEED = 0\nOUTPUT_DIR = ""\n\n'
        f"# %%\nimport subprocess, sys, time, pathlib\nproc = subprocess.Popen([sys.executable, '-c', {child!r}])\n"
        f"while not pathlib.Path({str(ready)!r}).exists():\n    time.sleep(0.05)\n\n"
        "# %%\nfrom cislunar.publish.claims import Claim\nfrom cislunar.publish.report import ComparisonTable\n"
        "ComparisonTable('t').add(Claim('x [-]', kind='derived').judge(1)).display()\n"
    )
    notebooks.run_notebook(src, quick=True, output_dir=tmp_path / "build")
    time.sleep(1.0)  # a signal sent during shutdown would have been handled by now
    assert not marker.exists(), "the kernel's process group received SIGINT at shutdown"

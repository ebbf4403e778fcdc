"""A notebook run by hand (JupyterLab, or papermill without the runner) writes into ``build-scratch/`` and never
into ``build/``, and its outputs hold plain text, not widgets (issue 19, "Outputs").

Two halves: every notebook source sends each figure through ``save_figure(..., output_dir=out)`` with
``out = OUTPUT_DIR or None`` and ``OUTPUT_DIR = ""`` by default, and writes no file any other way (read with
``ast``); and a notebook built on that idiom, executed by hand with papermill in a stand-in checkout whose
``build/`` already holds a run, leaves ``build/`` byte for byte as it was and puts its figure in
``build-scratch/figures``.
"""

from __future__ import annotations

import ast
import hashlib
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import jupytext
import pytest

from cislunar.publish import notebooks

pytestmark = pytest.mark.xdist_group("hand-runs")

SOURCES = notebooks.discover()
#: Calls that would write a file behind save_figure's back.
WRITERS = {"savefig", "save", "savez", "savez_compressed", "savetxt", "to_csv", "write_text", "write_bytes", "dump",
           "mkdir", "open", "imsave"}


def _cells(source: Path):
    return jupytext.read(source).cells


def _parameters(source: Path) -> dict:
    cell = next(c for c in _cells(source) if "parameters" in c.metadata.get("tags", []))
    return {t.id: n.value for n in ast.parse(cell.source).body if isinstance(n, ast.Assign)
            for t in n.targets if isinstance(t, ast.Name)}


def _code(source: Path) -> ast.Module:
    code = "\n".join(c.source for c in _cells(source) if c.cell_type == "code")
    return ast.parse("\n".join(line for line in code.splitlines() if not line.lstrip().startswith(("%", "!"))))


@pytest.mark.parametrize("source", SOURCES, ids=[p.stem for p in SOURCES])
def test_every_figure_goes_through_save_figure_with_the_output_dir_parameter(source):
    params = _parameters(source)
    assert "OUTPUT_DIR" in params and isinstance(params["OUTPUT_DIR"], ast.Constant)
    assert params["OUTPUT_DIR"].value == ""
    tree = _code(source)
    outs = [n for n in ast.walk(tree) if isinstance(n, ast.Assign) and any(
        isinstance(t, ast.Name) and t.id == "out" for t in n.targets)]
    assert [ast.unparse(n.value) for n in outs] == ["OUTPUT_DIR or None"]
    saves, writers = 0, []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        name = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
        if name == "save_figure":
            saves += 1
            kw = {k.arg: ast.unparse(k.value) for k in node.keywords}
            assert kw.get("output_dir") == "out", f"{source.name}: {ast.unparse(node)}"
        elif name in WRITERS:
            writers.append(ast.unparse(node))
    assert saves >= 1 and writers == [], writers


def _tree_digest(folder: Path) -> dict:
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


HAND_RUN = '''\
# %% tags=["parameters"]
QUICK = False
SEED = 0
OUTPUT_DIR = ""

# %%
import matplotlib.pyplot as plt

from cislunar.publish import plotting
from cislunar.utils.progress import progress

out = OUTPUT_DIR or None
total = 0
for i in progress(range(50), desc="a long loop"):
    total += i
fig, ax = plt.subplots()
ax.plot([0.0, 1.0], [0.0, float(total)])
ax.set_xlabel("t [s]")
ax.set_ylabel("sum [-]")
_ = plotting.save_figure(fig, "hand_run_check", output_dir=out)
print("total", total)
'''


def test_a_hand_run_writes_to_build_scratch_and_leaves_build_untouched(tmp_path):
    repo = tmp_path / "repo"  # a stand-in checkout, found through CISLUNAR_ROOT as the package finds the real one
    (repo / "build" / "figures").mkdir(parents=True)
    (repo / "build" / "figures" / "hand_run_check.png").write_bytes(b"a full run's figure")
    (repo / "build" / "report.md").write_text("a full run's report\n")
    before = _tree_digest(repo / "build")
    nb_path = tmp_path / "hand_run.ipynb"
    jupytext.write(jupytext.reads(HAND_RUN, fmt="py:percent"), nb_path)
    env = {k: v for k, v in os.environ.items() if k not in ("CISLUNAR_PROGRESS", "CISLUNAR_ROOT")}
    env.update(CISLUNAR_ROOT=str(repo), JUPYTER_PREFER_ENV_PATH="1")
    executed = tmp_path / "hand_run.out.ipynb"
    proc = subprocess.run([sys.executable, "-m", "papermill", str(nb_path), str(executed), "-k", "python3",
                           "--cwd", str(tmp_path), "--no-progress-bar"],
                          env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert _tree_digest(repo / "build") == before  # nothing in build/ added, changed or removed
    assert (repo / "build-scratch" / "figures" / "hand_run_check.png").is_file()
    nb = jupytext.read(executed)
    outputs = [o for c in nb.cells for o in c.get("outputs", [])]
    text = "".join(o.get("text", "") for o in outputs if o.get("output_type") == "stream")
    assert "total 1225" in text and "a long loop" in text  # the plain-text bar, on stderr
    assert not any("application/vnd.jupyter.widget-view+json" in o.get("data", {}) for o in outputs)
    assert "without encryption" not in text
    # nor on the terminal: the bootstrap installs the kernel with --IPKernelApp.log_level=ERROR (Makefile)
    assert "without encryption" not in proc.stderr, proc.stderr[-2000:]


def test_the_static_check_catches_a_figure_written_into_build(tmp_path):
    bad = tmp_path / "99_bad.py"
    bad.write_text(HAND_RUN.replace('output_dir=out)', 'output_dir="build")'))
    with pytest.raises(AssertionError):
        test_every_figure_goes_through_save_figure_with_the_output_dir_parameter(bad)
    bad.write_text(HAND_RUN + "\nfig.savefig('build/figures/x.png')\n")
    with pytest.raises(AssertionError):
        test_every_figure_goes_through_save_figure_with_the_output_dir_parameter(bad)
    good = tmp_path / "99_good.py"
    good.write_text(textwrap.dedent(HAND_RUN))
    test_every_figure_goes_through_save_figure_with_the_output_dir_parameter(good)

"""Every size or setting of a notebook is a parameter honoured as given, and every notebook with a sweep or a
Monte Carlo takes an executor from its parameters (issue 19, "Parameters that work" and "An executor parameter").

Read from the sources with ``ast``: ``QUICK`` is only ever used to pick the default of a parameter left at
``None`` (inside ``P if P is not None else ...``), no code cell overwrites a parameter otherwise, and each
``open_executor`` call gets ``WORKERS`` (or the value resolved from it) and ``SCHEDULER``.  That a value given
with ``-p`` reaches the notebook and changes its output is ``tests/publish/test_runner.py``'s job.
"""

from __future__ import annotations

import ast
from pathlib import Path

import jupytext
import pytest

from cislunar.publish import notebooks

SOURCES = notebooks.discover()
COMMON = {"QUICK", "SEED", "OUTPUT_DIR"}


def _split(source: Path) -> tuple[dict, ast.Module]:
    cells = jupytext.read(source).cells
    params = next(c for c in cells if "parameters" in c.metadata.get("tags", []))
    names = {t.id: n.value for n in ast.parse(params.source).body if isinstance(n, ast.Assign)
             for t in n.targets if isinstance(t, ast.Name)}
    code = "\n".join(c.source for c in cells if c.cell_type == "code" and c is not params)
    code = "\n".join(line for line in code.splitlines() if not line.lstrip().startswith(("%", "!")))
    return names, ast.parse(code)


def _parents(tree):
    parent = {}
    for node in ast.walk(tree):
        for child in ast.iter_child_nodes(node):
            parent[child] = node
    return parent


def _guarded_default(node, parent) -> str | None:
    """The parameter P when ``node`` sits in the ``else`` branch of ``P if P is not None else ...``."""
    while node in parent:
        up = parent[node]
        if isinstance(up, ast.IfExp) and node is up.orelse:
            t = up.test
            if (isinstance(t, ast.Compare) and isinstance(t.left, ast.Name) and len(t.ops) == 1
                    and isinstance(t.ops[0], ast.IsNot) and isinstance(t.comparators[0], ast.Constant)
                    and t.comparators[0].value is None):
                return t.left.id
        node = up
    return None


def check_source(source: Path) -> None:
    params, tree = _split(source)
    assert COMMON <= set(params), f"{source.name}: the parameters cell lacks {COMMON - set(params)}"
    parent = _parents(tree)
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and node.id == "QUICK" and isinstance(node.ctx, ast.Load):
            guard = _guarded_default(node, parent)
            assert guard in params, (f"{source.name} line {node.lineno}: QUICK used outside 'P if P is not None "
                                     f"else ...' (it may only pick the default of a parameter left at None)")
        if isinstance(node, (ast.Assign, ast.AugAssign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                for name in (n.id for n in ast.walk(t) if isinstance(n, ast.Name) and n.id in params):
                    guarded = node.value is not None and any(_guarded_default(n.orelse, parent) == name
                                                             for n in ast.walk(node.value) if isinstance(n, ast.IfExp))
                    assert guarded, f"{source.name} line {node.lineno}: parameter {name} overwritten"
    calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call)
             and (getattr(n.func, "id", None) or getattr(n.func, "attr", None)) == "open_executor"]
    if calls:
        assert {"WORKERS", "SCHEDULER"} <= set(params), f"{source.name}: runs an executor without WORKERS/SCHEDULER"
        for call in calls:
            args = [ast.unparse(a) for a in call.args] + [ast.unparse(k.value) for k in call.keywords]
            assert "SCHEDULER" in args, f"{source.name}: {ast.unparse(call)} ignores SCHEDULER"
            assert any("WORKERS" in a or a == "workers" for a in args), f"{source.name}: {ast.unparse(call)}"


@pytest.mark.parametrize("source", SOURCES, ids=[p.stem for p in SOURCES])
def test_quick_only_picks_defaults_and_executors_come_from_the_parameters(source):
    check_source(source)


def test_every_notebook_with_a_sweep_or_monte_carlo_has_an_executor():
    with_executor = {p.stem[:3].rstrip("_") for p in SOURCES if "open_executor(" in p.read_text()}
    # 01 is the one chapter with nothing random and nothing parallel (its parameters cell says so)
    assert with_executor == {p.stem[:3].rstrip("_") for p in SOURCES} - {"01"}


BASE = '# %% tags=["parameters"]\nQUICK = False\nSEED = 0\nOUTPUT_DIR = ""\nN = None\nWORKERS = 1\nSCHEDULER = ""\n'


@pytest.mark.parametrize("body, message", [
    ("# %%\nn = 10 if QUICK else 100\n", "QUICK used outside"),
    ("# %%\nN = 10\n", "parameter N overwritten"),
    ("# %%\nfrom x import open_executor\nwith open_executor(WORKERS, '') as ex:\n    pass\n", "ignores SCHEDULER"),
])
def test_the_checker_catches_each_break(tmp_path, body, message):
    bad = tmp_path / "99_bad.py"
    bad.write_text(BASE + body)
    with pytest.raises(AssertionError, match=message):
        check_source(bad)
    good = tmp_path / "99_good.py"
    good.write_text(BASE + "# %%\nn = N if N is not None else (10 if QUICK else 100)\n"
                    "from x import open_executor\nwith open_executor(WORKERS, SCHEDULER) as ex:\n    pass\n")
    check_source(good)


@pytest.mark.parametrize("source", SOURCES, ids=[p.stem for p in SOURCES])
def test_papermill_lists_every_parameter_with_its_default_and_help(source, caplog):
    """``papermill --help-notebook`` (papermill's own reading of the parameters cell) names every parameter.

    papermill drops, with an "Unable to parse line" warning in every run's log, any parameter line holding more than
    one ``=``, so a help comment must not contain one (it used to: ``0.002 TU = 12.5 min``).
    """
    from papermill.translators import PythonTranslator

    cell = next(c for c in jupytext.read(source).cells if "parameters" in c.metadata.get("tags", []))
    with caplog.at_level("WARNING", logger="papermill"):
        listed = {p.name: p for p in PythonTranslator.inspect(cell)}
    assert not [r.getMessage() for r in caplog.records if "Unable to parse" in r.getMessage()]
    assert set(listed) == set(_split(source)[0])
    assert all(p.help for name, p in listed.items() if name not in COMMON), "every parameter explains itself"

"""Chapter statistics: how much of each notebook source is prose and how much is code.

A notebook is a chapter: prose, a call, a plot.  :func:`chapter_statistics` counts the lines of a jupytext
py:percent source by kind, so the balance can be printed (``python -m cislunar.publish.chapters``, the table in
``environment.md``) and held by a test (prose at least equal to code in every notebook).

Counting rules: the jupytext header (the ``# ---`` block at the top) and cell markers (``# %%``) are not counted;
a *prose* line is a non-blank line of a markdown cell; a *code* line is a non-blank line of a code cell that is not
only a comment; comment lines inside code cells are counted apart.
"""

from __future__ import annotations

import argparse
import os
import re
from dataclasses import dataclass
from pathlib import Path

__all__ = ["ChapterStatistics", "chapter_statistics", "statistics_table", "main"]

_MARKER = re.compile(r"^# %%(.*)$")


@dataclass(frozen=True)
class ChapterStatistics:
    """Line counts of one notebook source.

    Attributes
    ----------
    name : str
        The source's stem (``05_test_case_1``).
    prose_lines, code_lines, comment_lines : int
        Non-blank lines of markdown cells; non-blank, non-comment lines of code cells; comment lines of code cells.
    code_cells, markdown_cells : int
    """

    name: str
    prose_lines: int
    code_lines: int
    comment_lines: int
    code_cells: int
    markdown_cells: int

    @property
    def prose_to_code(self) -> float:
        """Prose lines per code line (``inf`` for a notebook without code)."""
        return self.prose_lines / self.code_lines if self.code_lines else float("inf")


def chapter_statistics(source: str | os.PathLike) -> ChapterStatistics:
    """Count prose and code lines of a jupytext py:percent notebook source.

    Parameters
    ----------
    source : path-like
        A ``notebooks/NN_topic.py`` file.
    """
    if not isinstance(source, (str, os.PathLike)):
        raise TypeError(f"source must be a path to a notebook source; got {type(source).__name__}")
    path = Path(source)
    if not path.is_file():
        raise ValueError(f"source must be an existing notebook source file; got {str(path)!r}")
    lines = path.read_text(encoding="utf-8").splitlines()
    i = 0
    if lines and lines[0].strip() == "# ---":  # jupytext header
        i = 1
        while i < len(lines) and lines[i].strip() != "# ---":
            i += 1
        i += 1
    kind = None
    prose = code = comments = n_code = n_md = 0
    for line in lines[i:]:
        m = _MARKER.match(line)
        if m:
            kind = "markdown" if "[markdown]" in m.group(1) else "code"
            n_md += kind == "markdown"
            n_code += kind == "code"
            continue
        if not line.strip() or kind is None:
            continue
        if kind == "markdown":
            prose += 1
        elif line.lstrip().startswith("#"):
            comments += 1
        else:
            code += 1
    return ChapterStatistics(path.stem, prose, code, comments, n_code, n_md)


def statistics_table(sources) -> str:
    """A Markdown table of :func:`chapter_statistics` for several sources, with a total row."""
    if isinstance(sources, (str, bytes, os.PathLike)) or not hasattr(sources, "__iter__"):
        raise TypeError(f"sources must be an iterable of notebook source paths; got {type(sources).__name__}")
    rows = [chapter_statistics(s) for s in sources]
    out = ["| notebook | prose lines | code lines | code comments | prose / code |", "|---|---:|---:|---:|---:|"]
    for r in rows:
        out.append(f"| {r.name} | {r.prose_lines} | {r.code_lines} | {r.comment_lines} | {r.prose_to_code:.2f} |")
    p, c, k = (sum(getattr(r, a) for r in rows) for a in ("prose_lines", "code_lines", "comment_lines"))
    out.append(f"| total | {p} | {c} | {k} | {p / c if c else float('inf'):.2f} |")
    return "\n".join(out)


def main(argv=None) -> int:
    """``python -m cislunar.publish.chapters [sources...]``: print the table (default: every notebook)."""
    parser = argparse.ArgumentParser(prog="python -m cislunar.publish.chapters", description=__doc__.split("\n\n")[0])
    parser.add_argument("sources", nargs="*", help="notebook sources (default: notebooks/*.py)")
    args = parser.parse_args(argv)
    from_root = Path(__file__).resolve().parents[2] / "notebooks"
    sources = args.sources or sorted(from_root.glob("[0-9]*.py"))
    print(statistics_table(sources))
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())

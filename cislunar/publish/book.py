"""Build the static HTML book from already executed notebooks (``make book``; the last step of ``make reproduce``).

Usage::

    python -m cislunar.publish.book                      # build/notebooks/*.ipynb -> build/book/index.html
    python -m cislunar.publish.book --build-dir DIR      # another build directory (the tests use a temporary one)

Nothing is executed again: the executed notebooks written by :mod:`cislunar.publish.notebooks` are copied into a staging
source tree ``<build>/.book/src/`` together with a generated index page (title, paper sections and summary of each
notebook, read from the notebook's own opening cell, plus the status counts of its closing table), the
paper-vs-reproduction report and a page citing the four papers; Sphinx with myst-nb (``nb_execution_mode = "off"``)
and sphinx-book-theme then renders it to ``<build>/book/``, configured by ``book/conf.py``.

The copies are cleaned for reading: parameters cells show no machine paths, papermill's path metadata is dropped,
carriage-return progress updates in stream output are collapsed to their final state (as a terminal shows them),
and a note at the top of each page says in which mode (full or quick) and how long the notebook ran.

The book reads offline: MathJax is served from ``_static/mathjax`` (copied from the ``sphinx-mathjax-offline``
package), and no page loads or links anything outside the book (``tests/publish/test_book.py`` checks this).
"""

from __future__ import annotations

import argparse
import copy
import json
import pkgutil
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import cislunar
from cislunar.publish import notebooks as runner
from cislunar.publish import provenance
from cislunar.publish.claims import STATUSES
from cislunar.publish.report import REPORT_METADATA_KEY
from cislunar.utils import paths

__all__ = ["BookError", "NotebookEntry", "read_entries", "stage", "build_book", "main"]

_STATUS_WORDS = STATUSES


class BookError(RuntimeError):
    """The book cannot be built (no executed notebooks, missing tools, or Sphinx failed); the message says why."""


@dataclass(frozen=True)
class NotebookEntry:
    """What the index page says about one notebook."""

    name: str
    title: str
    learn: str
    sections: str
    mode: str | None
    seconds: float | None
    statuses: dict
    executed: bool


def book_config_dir() -> Path:
    """``book/`` in the repository: ``conf.py``, static files and the hand-written pages."""
    return paths.repo_root() / "book"


def _source_text(cell) -> str:
    src = cell.get("source", "")
    return "".join(src) if isinstance(src, list) else src


def _opening(md: str) -> tuple[str, str, str]:
    """Title, "What you will learn" and "Paper sections followed" paragraphs of a notebook's opening cell."""
    title = ""
    for line in md.splitlines():
        if line.startswith("# "):
            title = line[2:].strip()
            break
    raw = [p.strip() for p in re.split(r"\n\s*\n", md)]
    paras = [" ".join(p.split()) for p in raw]

    def labelled(label):
        for i, p in enumerate(paras):
            m = re.match(r"\*\*" + label + r"[^*]*\*\*\s*(.*)", p, flags=re.IGNORECASE)
            if m:
                text = m.group(1).strip()
                # A paragraph that announces a list ("...:") keeps the list that follows it.
                if text.endswith(":") and i + 1 < len(raw) and re.match(r"[*+-] ", raw[i + 1]):
                    text += "\n\n" + raw[i + 1]
                return text
        return ""

    return title, labelled("What you will learn"), labelled("Paper sections? followed")


def _statuses(report_md: str) -> dict:
    """Count the status words in the last column of a notebook's closing table(s)."""
    counts: dict = {}
    for line in report_md.splitlines():
        if not line.startswith("| ") or "| status |" in line or set(line) <= set("|-: "):
            continue
        cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
        if len(cells) < 4:
            continue
        status = cells[3].lower()
        for word in _STATUS_WORDS:
            if status.startswith(word):
                counts[word] = counts.get(word, 0) + 1
                break
        else:
            counts["other"] = counts.get("other", 0) + 1
    return counts


def _notebook_mode(nb: dict) -> tuple[str | None, float | None]:
    pm = nb.get("metadata", {}).get("papermill", {})
    params = pm.get("parameters", {})
    mode = None if "QUICK" not in params else ("quick" if params["QUICK"] else "full")
    return mode, pm.get("duration")


def _first_markdown_of_percent_source(path: Path) -> str:
    """Text of the first ``# %% [markdown]`` cell of a jupytext py:percent file (without importing jupytext)."""
    lines, inside = [], False
    for line in path.read_text().splitlines():
        if line.startswith("# %%"):
            if inside:
                break
            inside = "[markdown]" in line
            continue
        if inside:
            lines.append(line[2:] if line.startswith("# ") else line.lstrip("#"))
    return "\n".join(lines)


def read_entries(build: Path) -> list[NotebookEntry]:
    """One entry per notebook source in ``notebooks/`` and per executed notebook in ``<build>/notebooks``.

    Executed notebooks come first-hand from their own opening cell; a source that has not been executed in this
    build is listed from its jupytext source, marked ``executed=False``.
    """
    executed = {p.stem: p for p in sorted((build / "notebooks").glob("[0-9][0-9]*_*.ipynb"))}
    names = sorted(set(executed) | {p.stem for p in runner.discover()})
    entries = []
    for name in names:
        if name in executed:
            nb = json.loads(executed[name].read_text())
            md = next((_source_text(c) for c in nb["cells"] if c["cell_type"] == "markdown"), "")
            mode, seconds = _notebook_mode(nb)
        else:
            md = _first_markdown_of_percent_source(runner.notebooks_dir() / f"{name}.py")
            mode, seconds = None, None
        title, learn, sections = _opening(md)
        rep = build / "report" / f"{name}.md"
        statuses = _statuses(rep.read_text()) if (name in executed and rep.is_file()) else {}
        entries.append(NotebookEntry(name, title or name, learn, sections, mode, seconds, statuses,
                                     name in executed))
    return entries


def _collapse_carriage_returns(text: str) -> str:
    """What a terminal shows: on each line, only the text after the last carriage return survives."""
    out = []
    for line in text.split("\n"):
        if "\r" in line:
            parts = [p for p in line.split("\r")]
            kept = next((p for p in reversed(parts) if p), "")
            line = kept
        out.append(line)
    return "\n".join(out)


def _terminal_streams(outputs: list) -> list:
    """Merge consecutive writes to the same stream and keep what a terminal would show of them.

    A text progress bar arrives as many small writes, each starting with a carriage return; only its final state
    survives.  The order of stdout, stderr and rich outputs is kept.
    """
    merged = []
    for out in outputs:
        if out.get("output_type") == "stream":
            text = out.get("text", "")
            text = "".join(text) if isinstance(text, list) else text
            last = merged[-1] if merged else None
            if last is not None and last.get("output_type") == "stream" and last.get("name") == out.get("name"):
                last["text"] += text
                continue
            out = dict(out, text=text)
        merged.append(out)
    for out in merged:
        if out.get("output_type") == "stream":
            out["text"] = _collapse_carriage_returns(out["text"])
    return [o for o in merged if o.get("output_type") != "stream" or o["text"].strip()]


def _display_path(path: str, build: Path) -> str:
    """A path as the book shows it: relative to the repository when inside it, else ``<build>/...``."""
    root = paths.repo_root().resolve()
    p = Path(path)
    try:
        return str(p.resolve().relative_to(root))
    except ValueError:
        pass
    try:
        rel = p.resolve().relative_to(build.resolve())
        return "<build>" + ("" if str(rel) == "." else f"/{rel}")
    except ValueError:
        return "<path>"


def clean_notebook(nb: dict, build: Path, *, source_name: str) -> dict:
    """A copy of an executed notebook ready to render: no machine paths in parameters, terminal-like streams.

    Outputs other than streams are left exactly as executed, so that a notebook that prints a path or raises is
    still visible in the book (and caught by ``tests/publish/test_book.py``).
    """
    nb = copy.deepcopy(nb)
    pm = nb.get("metadata", {}).get("papermill")
    if pm is not None:
        for key in ("input_path", "output_path"):
            pm.pop(key, None)
        params = pm.get("parameters", {})
        if isinstance(params.get("OUTPUT_DIR"), str) and params["OUTPUT_DIR"]:
            params["OUTPUT_DIR"] = _display_path(params["OUTPUT_DIR"], build)
    for cell in nb["cells"]:
        tags = cell.get("metadata", {}).get("tags", [])
        if cell["cell_type"] == "code" and ("injected-parameters" in tags or "parameters" in tags):
            src = _source_text(cell)
            src = re.sub(r'(OUTPUT_DIR\s*=\s*)(["\'])(.+?)\2',
                         lambda m: f'{m.group(1)}"{_display_path(m.group(3), build)}"', src)
            cell["source"] = src
        if cell.get("outputs"):
            cell["outputs"] = _terminal_streams(cell["outputs"])
        if cell["cell_type"] == "code" and any(o.get("metadata", {}).get(REPORT_METADATA_KEY)
                                               for o in cell.get("outputs", [])):
            meta = cell.setdefault("metadata", {})
            meta["tags"] = sorted(set(meta.get("tags", [])) | {"hide-input"})  # the table shows; its code folds
    mode, seconds = _notebook_mode(nb)
    how = {"full": " at full fidelity", "quick": " in **quick mode**"}.get(mode, "")
    took = f" in {seconds:.0f} s" if seconds is not None else ""
    caveat = (" Quick mode shrinks sample sizes and grids but runs the same science; `make reproduce` gives the "
              "paper-scale numbers." if mode == "quick" else "")
    run = nb.get("metadata", {}).get(provenance.METADATA_KEY, {})
    origin = (f" Run {run['run_id']}, commit {run.get('commit', 'unknown')}, started {run.get('started', '?')}."
              if run.get("run_id") else "")
    note = (f"```{{note}}\nExecuted headless{how}{took} by `python -m cislunar.publish.notebooks` from "
            f"`notebooks/{source_name}.py`; the book shows that run without executing anything again.{origin}"
            f"{caveat}\n```")
    banner = {"cell_type": "markdown", "id": "cislunar-book-run-note", "metadata": {}, "source": note}
    first_md = next((i for i, c in enumerate(nb["cells"]) if c["cell_type"] == "markdown"), -1)
    nb["cells"].insert(first_md + 1, banner)
    return nb


def _fmt_status(counts: dict) -> str:
    if not counts:
        return ""
    order = list(_STATUS_WORDS) + ["other"]
    return ", ".join(f"{counts[w]} {w}" for w in order if w in counts)


def _index_markdown(entries: list[NotebookEntry], build: Path) -> str:
    intro_file = book_config_dir() / "intro.md"
    intro = intro_file.read_text().strip() if intro_file.is_file() else "# cislunar"
    modes = sorted({e.mode for e in entries if e.executed and e.mode})
    lines = [intro, ""]
    if modes == ["quick"]:
        lines += ["```{warning}", "This book was built from a **quick-mode** run (reduced sample sizes and grids, "
                  "same science). The paper-scale numbers come from `make reproduce`.", "```", ""]
    elif len(modes) > 1:
        lines += ["```{warning}", f"This build mixes notebooks executed in {' and '.join(modes)} mode.", "```", ""]
    lines += ["## The notebooks", ""]
    for e in entries:
        if e.executed:
            lines.append(f"### [{e.title}](notebooks/{e.name}.ipynb)")
        else:
            lines.append(f"### {e.title}")
        lines.append("")
        if e.sections:
            lines += [f"**Reproduces.** {e.sections}", ""]
        if e.learn:
            lines += [f"**What you will learn.** {e.learn}", ""]
        if e.executed:
            facts = [f"{e.mode} mode" if e.mode else "", f"{e.seconds:.0f} s" if e.seconds is not None else "",
                     _fmt_status(e.statuses)]
            facts = [f for f in facts if f]
            if facts:
                lines += [f"*Closing table:* {'; '.join(facts)}. See the [report](report.md).", ""]
        else:
            lines += [f"*Not executed in this build* (`python -m cislunar.publish.notebooks {e.name}`).", ""]
    lines += ["```{toctree}", ":hidden:", ":caption: Notebooks", ""]
    lines += [f"notebooks/{e.name}" for e in entries if e.executed]
    lines += ["```", "", "```{toctree}", ":hidden:", ":caption: Results and references", "", "report", "papers",
              "sources", "api/index", "```", ""]
    return "\n".join(lines)


def _report_markdown(build: Path, titles: dict) -> str:
    """``<build>/report.md`` with each section headed by its notebook's title, linked to the notebook's page."""
    rep = build / "report.md"
    if not rep.is_file():
        return "# Paper versus reproduction\n\nNo report in this build.\n"
    text = rep.read_text()

    def link(m):
        name = m.group(1)
        if name in titles:
            return f"## [{titles[name]}](notebooks/{name}.ipynb){m.group(2)}"
        return m.group(0)

    body = re.sub(r"^## (\d\d[a-z]?_\w+)(.*)$", link, text, flags=re.MULTILINE)
    return _insert_summary(body, build, titles)


def _insert_summary(report: str, build: Path, titles: dict) -> str:
    """A table of status counts per notebook (and in total) placed before the first section of the report."""
    rows, total = [], {}
    for path in sorted((build / "report").glob("*.md")):
        counts = _statuses(path.read_text())
        for k, v in counts.items():
            total[k] = total.get(k, 0) + v
        title = titles.get(path.stem, path.stem)
        rows.append([f"[{title}](notebooks/{path.stem}.ipynb)" if path.stem in titles else title]
                    + [str(counts.get(w, 0)) for w in _STATUS_WORDS])
    if not rows:
        return report
    head = "| notebook | " + " | ".join(_STATUS_WORDS) + " |"
    lines = ["## Summary", "", "Rows of each closing table by status word.", "", head,
             "|---|" + "---:|" * len(_STATUS_WORDS)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    lines.append("| **total** | " + " | ".join(f"**{total.get(w, 0)}**" for w in _STATUS_WORDS) + " |")
    summary = "\n".join(lines) + "\n\n"
    m = re.search(r"^## ", report, flags=re.MULTILINE)
    return report[:m.start()] + summary + report[m.start():] if m else report + "\n" + summary


def _papers_markdown() -> str:
    """The papers page: ``book/papers.md`` followed by the references of ``CITATION.cff``."""
    import yaml

    page = book_config_dir() / "papers.md"
    text = page.read_text().rstrip() + "\n" if page.is_file() else "# The papers\n"
    cff_path = paths.repo_root() / "CITATION.cff"
    if not cff_path.is_file():
        return text
    cff = yaml.safe_load(cff_path.read_text())

    def names(authors):
        return ", ".join(a.get("name") or f"{a.get('given-names', '')} {a.get('family-names', '')}".strip()
                         for a in authors)

    lines = ["", "## The four papers", ""]
    for ref in cff.get("references", []):
        where = ref.get("journal") or ref.get("conference", {}).get("name") or ref.get("collection-title") or ""
        bits = [names(ref.get("authors", [])), f"*{ref['title']}*", where]
        if ref.get("volume"):
            bits.append(f"vol. {ref['volume']}")
        if ref.get("start"):
            bits.append(f"pp. {ref['start']}-{ref.get('end', '')}".rstrip("-"))
        bits.append(str(ref.get("year", "")))
        ids = [str(i["value"]) for i in ref.get("identifiers", [])]
        if ref.get("doi"):
            ids.insert(0, f"doi {ref['doi']}")
        lines.append("- " + ", ".join(b for b in bits if b) + (f" ({'; '.join(ids)})" if ids else "") + ".")
        if ref.get("notes"):
            lines.append(f"  {ref['notes']}")
    lines += ["", "## Citing this reproduction", "",
              f"{names(cff.get('authors', []))}, *{cff.get('title', '')}*, version {cff.get('version', '')}. "
              "Please cite the papers above as well; the machine-readable form of both is `CITATION.cff` in the "
              "repository.", ""]
    return text + "\n".join(lines)


def stage(build: Path) -> Path:
    """Write the book's source tree ``<build>/.book/src/`` from the executed notebooks; returns its path.

    Raises
    ------
    BookError
        When ``<build>/notebooks`` holds no executed notebook.
    """
    executed = sorted((build / "notebooks").glob("[0-9][0-9]*_*.ipynb"))
    if not executed:
        raise BookError(f"no executed notebooks in {build / 'notebooks'}; run `make reproduce` (or "
                        "`python -m cislunar.publish.notebooks`) first")
    src = _work_dir(build) / "src"
    if src.exists():
        shutil.rmtree(src)
    (src / "notebooks").mkdir(parents=True)
    for path in executed:
        nb = clean_notebook(json.loads(path.read_text()), build, source_name=path.stem)
        (src / "notebooks" / path.name).write_text(json.dumps(nb, indent=1))
    entries = read_entries(build)
    (src / "index.md").write_text(_index_markdown(entries, build))
    (src / "report.md").write_text(_report_markdown(build, {e.name: e.title for e in entries if e.executed}))
    (src / "papers.md").write_text(_papers_markdown())
    shutil.copyfile(book_config_dir() / "sources.md", src / "sources.md")
    _write_api_pages(src / "api")
    return src


def _api_modules() -> dict:
    """``{wing: [module names]}`` of the package, found on disk (wings in the order a reader meets them)."""
    order = ["cr3bp", "sensing", "estimation", "guidance", "papers", "publish", "utils"]
    found: dict = {w: [] for w in order}
    for info in pkgutil.walk_packages(cislunar.__path__, "cislunar."):
        parts = info.name.split(".")
        if info.ispkg or parts[-1].startswith("_") or len(parts) < 3:
            continue
        found.setdefault(parts[1], []).append(info.name)
    return {w: sorted(m) for w, m in found.items() if m}


def _api_page(module: str) -> str:
    """The API page of a module: its subpackage (``cislunar.cr3bp``; one per paper: ``cislunar.papers.wolf_jones``)."""
    parts = module.split(".")
    return ".".join(parts[:3] if parts[1] == "papers" else parts[:2])


def _write_api_pages(folder: Path) -> None:
    """One page per subpackage under ``api/``, a section per module rendered by autodoc from its numpydoc
    docstrings (napoleon).

    Every module keeps its anchor (``#module-<name>``) and every object its own (``#<module>.<name>``); the index
    links each module through the Python domain.  A page per subpackage rather than per module keeps the book's
    navigation, which Sphinx renders on every page, short (10 pages instead of 84; with ``toc_object_entries = False``
    in ``book/conf.py`` Sphinx's time for the book fell from about 42 s to 23 s of CPU on 13 full notebooks,
    2026-11-26).
    """
    folder.mkdir(parents=True, exist_ok=True)
    wings = _api_modules()
    index = ["# API reference", "",
             "Every module of the package, from its docstrings (numpydoc: parameters with units and frames), one "
             "page per subpackage. Methods come first, by family; then one package per paper, publishing and "
             "utilities.", ""]
    toc = ["```{toctree}", ":maxdepth: 1", ""]
    pages: dict = {}
    for wing, modules in wings.items():
        index += [f"## {wing}", ""]
        for mod in modules:
            page = _api_page(mod)
            if page not in pages:
                pages[page] = []
                toc.append(page)
                index.append(f"- [{page}]({page}.md)")
            pages[page].append(mod)
            index.append(f"  - {{py:mod}}`{mod}`")
        index.append("")
    for page, modules in pages.items():
        text = [f"# {page}", ""]
        for mod in modules:
            text += [f"## {mod}", "", "```{eval-rst}", f".. automodule:: {mod}", "   :members:",
                     "   :show-inheritance:", "```", ""]
        (folder / f"{page}.md").write_text("\n".join(text))
    (folder / "index.md").write_text("\n".join(index + ["", *toc, "```", ""]))


def _work_dir(build: Path) -> Path:
    """``<build>/.book``: the staged sources, Sphinx's doctrees and myst-nb's output files (kept for debugging)."""
    return build / ".book"


def _mathjax_dir() -> Path:
    """The MathJax 3 distribution shipped by the ``sphinx-mathjax-offline`` package."""
    from importlib import metadata

    try:
        dist = metadata.distribution("sphinx-mathjax-offline")
    except metadata.PackageNotFoundError:
        raise BookError("the book needs the 'book' extra: pip install -e '.[book]' (sphinx-mathjax-offline "
                        "is missing)") from None
    for f in dist.files or []:
        if f.name == "tex-chtml.js" and f.parent.name == "mathjax":
            return Path(dist.locate_file(f)).parent
    raise BookError("sphinx-mathjax-offline is installed but holds no mathjax/tex-chtml.js")


def build_book(build_dir=None, *, out_dir=None, quiet: bool = True, expected=None) -> Path:
    """Stage and render the book; returns ``<out>/index.html``.

    Parameters
    ----------
    build_dir : path-like, optional
        Build directory holding ``notebooks/*.ipynb`` and ``report.md`` (default ``build/``).
    out_dir : path-like, optional
        Where the HTML goes (default ``<build>/book``).
    quiet : bool
        Pass ``-q`` to Sphinx (warnings are still printed).
    expected : iterable of str, optional
        Notebooks the build must hold (default: every notebook source).

    Raises
    ------
    cislunar.publish.provenance.IncompleteBuildError
        When the build is partial, holds a failed notebook or mixes runs (:func:`provenance.audit_build`); the
        message names every problem.
    BookError
        When there is nothing to build, a tool is missing, or Sphinx fails (its output is in the message).
    """
    build = paths.build_dir(build_dir)
    names = [s.stem for s in runner.discover()] if expected is None else list(expected)
    problems = provenance.audit_build(build, names)
    if problems:
        raise provenance.IncompleteBuildError(build, problems)
    out = Path(out_dir) if out_dir is not None else build / "book"
    mathjax = _mathjax_dir()
    src = stage(build)
    html = _work_dir(build) / "html"  # myst-nb writes its files next to Sphinx's output directory
    if html.exists():
        shutil.rmtree(html)
    cmd = [sys.executable, "-m", "sphinx", "-b", "html", "-c", str(book_config_dir()), "-d",
           str(_work_dir(build) / "doctrees"), "-E", "--keep-going", str(src), str(html)]
    if quiet:
        cmd.insert(3, "-q")
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.stdout.strip() and not quiet:
        print(proc.stdout, end="")
    if proc.stderr.strip():
        print(proc.stderr, end="", file=sys.stderr)
    if proc.returncode != 0 or not (html / "index.html").is_file():
        raise BookError(f"sphinx-build failed (exit {proc.returncode}):\n{proc.stderr[-4000:]}")
    # MathJax's TeX-to-HTML component and what it loads on demand (TeX extensions, fonts, accessibility, menu);
    # the other bundles (SVG output, MathML input, speech rules, node) are never loaded by the book.
    shutil.copytree(mathjax, html / "_static" / "mathjax", dirs_exist_ok=True,
                    ignore=shutil.ignore_patterns("sre", "svg", "*-svg*.js", "mml-*.js", "tex-mml-*.js",
                                                  "tex-chtml-full*.js", "node-main.js", "asciimath.js", "mml"))
    for template in (html / "_static").glob("*macros.html"):
        template.unlink()  # Jinja macro files the themes copy as static assets; no page uses them
    sources = html / "_sources"
    if sources.is_dir() and not any(sources.iterdir()):
        sources.rmdir()
    for leftover in (html / ".doctrees", html / ".buildinfo"):
        if leftover.is_dir():
            shutil.rmtree(leftover)
        elif leftover.exists():
            leftover.unlink()
    if out.exists():
        shutil.rmtree(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    shutil.move(str(html), str(out))
    return out / "index.html"


def main(argv=None) -> int:
    """Command-line entry point; returns the process exit status (1 if the build is refused, 2 outside a checkout)."""
    parser = argparse.ArgumentParser(prog="python -m cislunar.publish.book", description=__doc__.split("\n\n")[0])
    parser.add_argument("--build-dir", default=None, help="build directory with executed notebooks (default: build/)")
    parser.add_argument("--out-dir", default=None, help="HTML output directory (default: <build>/book)")
    parser.add_argument("-v", "--verbose", action="store_true", help="show Sphinx's progress output")
    args = parser.parse_args(argv)
    missing = runner._missing_checkout("book", "cislunar-book")
    if missing:
        print(missing, file=sys.stderr)
        return 2
    start = time.perf_counter()
    try:
        index = build_book(args.build_dir, out_dir=args.out_dir, quiet=not args.verbose)
    except (BookError, provenance.IncompleteBuildError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    print(f"book: {index} ({time.perf_counter() - start:.1f} s)", flush=True)
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())

"""The static HTML book: a page per notebook, links and images that resolve, nothing from the internet, no error
or widget output, no machine paths, and math typeset by MathJax in a real (headless Chromium) browser.

By default the book is built from this session's quick-mode notebook runs (shared with tests/test_notebooks.py,
see ``quick_runs`` in conftest.py) in a temporary directory.  With ``CISLUNAR_BOOK_BUILD=build`` the same checks run
on an existing build instead (``make check-book``, the last step of ``make reproduce``).

The checkers themselves are tested first on small planted pages, so that each would notice what it looks for.
"""

from __future__ import annotations

import base64
import fcntl
import json
import os
import re
import select
import shutil
import subprocess
import tempfile
import time
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest
from conftest import selected_notebooks

from cislunar.publish import book, notebooks, provenance
from cislunar.utils import paths

SOURCES = selected_notebooks()
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
EXTERNAL = re.compile(r"^\s*(?:[a-zA-Z][a-zA-Z0-9+.-]*:)?//|^\s*(?:https?|ftp|wss?):", re.IGNORECASE)
LOCAL_SCHEMES = ("data:", "javascript:", "mailto:", "blob:", "about:")
URL_ATTRS = {"href", "src", "srcset", "action", "poster", "data", "formaction", "background", "cite", "longdesc",
             "manifest", "xlink:href", "content"}


# ---------------------------------------------------------------------------------------------------- checkers
class _Page(HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.refs = []  # (tag, attribute, value)
        self.ids = set()
        self.styles = []
        self.classes = []
        self.text = []
        self._in_style = False

    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if value is None:
                continue
            if name in ("id", "name"):
                self.ids.add(value)
            if name == "class":
                self.classes.append((tag, value))
            if name == "style":
                self.styles.append(value)
            if name in URL_ATTRS and not (tag == "meta" and name == "content" and "://" not in value):
                if name == "srcset":
                    self.refs += [(tag, name, part.split()[0]) for part in value.split(",") if part.strip()]
                else:
                    self.refs.append((tag, name, value))
            if tag == "script" and name == "type" and "widget" in value:
                self.classes.append((tag, value))
        self._in_style = tag == "style"

    def handle_endtag(self, tag):
        self._in_style = False

    def handle_data(self, data):
        if self._in_style:
            self.styles.append(data)
        self.text.append(data)


class _Prose(HTMLParser):
    """The running text of a page: everything but code, outputs, scripts and (typeset) math."""

    SKIP_TAGS = {"pre", "code", "script", "style", "textarea"}
    SKIP_CLASSES = {"math", "highlight", "output", "cell_input"}
    VOID = {"br", "img", "hr", "meta", "link", "input", "wbr", "col", "area", "base", "source", "embed", "param",
            "track"}

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack = []
        self.out = []

    def handle_starttag(self, tag, attrs):
        if tag in self.VOID:
            return
        classes = set((dict(attrs).get("class") or "").split())
        self.stack.append((tag, tag in self.SKIP_TAGS or bool(classes & self.SKIP_CLASSES)))

    def handle_endtag(self, tag):
        for k in range(len(self.stack) - 1, -1, -1):
            if self.stack[k][0] == tag:
                del self.stack[k:]
                break

    def handle_data(self, data):
        if not any(skip for _, skip in self.stack):
            self.out.append(data)


def untypeset_tex(path: Path) -> list[str]:
    """TeX commands or dollar delimiters left in a page's running text: Markdown math that was not parsed."""
    prose = _Prose()
    prose.feed(path.read_text(encoding="utf-8", errors="replace"))
    text = "".join(prose.out)
    return [text[max(0, m.start() - 30):m.end() + 30] for m in re.finditer(r"\\[a-zA-Z]{2,}|\$\$?[^$\s]", text)]


_PARSED: dict = {}


def parse(path: Path) -> _Page:
    """The parsed page, read once per version of the file: four tests read every page of the built book (about 100
    pages, 10 MB of HTML) and share one parse; the key is path, size and modification time, so a page written again
    is parsed again (:func:`test_a_page_written_again_is_parsed_again`)."""
    stat = path.stat()
    key = (str(path.resolve()), stat.st_size, stat.st_mtime_ns)
    if key not in _PARSED:
        page = _Page()
        page.feed(path.read_text(encoding="utf-8", errors="replace"))
        _PARSED[key] = page
    return _PARSED[key]


_CSS_URL = re.compile(r"""url\(\s*['"]?([^'")]+)['"]?\s*\)|@import\s+['"]([^'"]+)['"]""")


def css_refs(text: str) -> list[str]:
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.DOTALL)  # comments are not loads
    return [a or b for a, b in _CSS_URL.findall(text)]


def check_site(root: Path) -> dict:
    """Every problem in the static site under ``root``: external references, broken local links and anchors.

    Returns ``{"external": [...], "broken": [...]}``, each entry ``"page: tag attr=value"``.
    """
    problems = {"external": [], "broken": []}
    pages = sorted(root.rglob("*.html"))
    parsed = {p.resolve(): parse(p) for p in pages}
    css_seen = set()

    def local_target(base: Path, ref: str):
        parts = urlsplit(ref)
        target = (base.parent / unquote(parts.path)).resolve() if parts.path else base.resolve()
        return target, parts.fragment

    for page, doc in parsed.items():
        rel = page.relative_to(root.resolve())
        refs = list(doc.refs) + [("style", "url", u) for s in doc.styles for u in css_refs(s)]
        for tag, attr, value in refs:
            v = value.strip()
            if not v or v.startswith("#") and tag != "a":
                continue
            if EXTERNAL.match(v):
                problems["external"].append(f"{rel}: <{tag} {attr}={v}>")
                continue
            if v.lower().startswith(LOCAL_SCHEMES) or (tag == "meta"):
                continue
            target, fragment = local_target(page, v)
            if not target.exists():
                problems["broken"].append(f"{rel}: <{tag} {attr}={v}> (no file)")
                continue
            if target.is_dir():
                if not (target / "index.html").is_file():
                    problems["broken"].append(f"{rel}: <{tag} {attr}={v}> (directory without index.html)")
                continue
            if fragment and target.suffix == ".html":
                ids = parsed[target].ids if target in parsed else parse(target).ids
                if unquote(fragment) not in ids:
                    problems["broken"].append(f"{rel}: <{tag} {attr}={v}> (no anchor #{fragment})")
            if target.suffix == ".css" and target not in css_seen:
                css_seen.add(target)
                for u in css_refs(target.read_text(encoding="utf-8", errors="replace")):
                    if EXTERNAL.match(u):
                        problems["external"].append(f"{target.relative_to(root.resolve())}: url({u})")
                    elif not u.lower().startswith(LOCAL_SCHEMES) and not u.startswith("#"):
                        t, _ = local_target(target, u)
                        if not t.exists():
                            problems["broken"].append(f"{target.relative_to(root.resolve())}: url({u}) (no file)")
    return problems


def rendered_problems(page: Path) -> list[str]:
    """Error output (tracebacks), widget output or widget state rendered on a notebook page."""
    html = page.read_text(encoding="utf-8", errors="replace")
    doc = parse(page)
    out = []
    for tag, cls in doc.classes:
        words = cls.split()
        if "traceback" in words or ("output" in words and "error" in words):
            out.append(f"error output <{tag} class={cls}>")
        if any("widget" in w for w in words) or "widget" in cls and tag == "script":
            out.append(f"widget output <{tag} {cls}>")
    for marker in ("application/vnd.jupyter.widget", "Traceback (most recent call last)"):
        if marker in html:
            out.append(f"{marker!r} on the page")
    return out


def notebook_problems(nb: dict) -> list[str]:
    """Error outputs, widget outputs or widget state in an executed notebook."""
    out = []
    if "widgets" in nb.get("metadata", {}):
        out.append("widget state in the notebook metadata")
    for i, cell in enumerate(nb["cells"]):
        for o in cell.get("outputs", []):
            if o.get("output_type") == "error":
                out.append(f"cell {i}: error output {o.get('ename')}")
            if any("widget" in k for k in o.get("data", {})):
                out.append(f"cell {i}: widget output")
            if o.get("output_type") == "stream" and "Traceback (most recent call last)" in "".join(o.get("text", "")):
                out.append(f"cell {i}: traceback on {o.get('name')}")
    return out


# -------------------------------------------------------------------------------------------- headless browser
class Chromium:
    """Headless Chromium driven over the DevTools protocol on a pipe (no extra Python package), network cut off.

    Every host name resolves to nothing (``--host-resolver-rules``), so a page that needs the internet shows it:
    its requests are recorded and fail.
    """

    FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
             "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-default-apps",
             "--host-resolver-rules=MAP * ~NOTFOUND", "--remote-debugging-pipe", "--hide-scrollbars"]

    def __init__(self, executable: str, *, width: int = 1280, height: int = 1600, timeout: float = 60.0):
        self.timeout = timeout
        self.profile = tempfile.mkdtemp(prefix="cislunar-chromium-")
        to_child_r, self._to_child = os.pipe()
        self._from_child, from_child_w = os.pipe()

        def wire():  # the protocol pipe is fd 3 (commands in) and fd 4 (replies out) in the browser
            a, b = os.dup(to_child_r), os.dup(from_child_w)
            os.dup2(a, 3)
            os.dup2(b, 4)

        self.proc = subprocess.Popen(
            [executable, *self.FLAGS, f"--user-data-dir={self.profile}", f"--window-size={width},{height}",
             "about:blank"],
            preexec_fn=wire, close_fds=False, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL)
        os.close(to_child_r)
        os.close(from_child_w)
        self._buf = b""
        self._id = 0
        self.events = []

    def _recv(self, deadline):
        while b"\0" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("no answer from Chromium")
            ready, _, _ = select.select([self._from_child], [], [], left)
            if ready:
                chunk = os.read(self._from_child, 1 << 20)
                if not chunk:
                    raise EOFError("Chromium closed the DevTools pipe")
                self._buf += chunk
        raw, self._buf = self._buf.split(b"\0", 1)
        return json.loads(raw)

    def call(self, method, params=None, session=None):
        self._id += 1
        msg = {"id": self._id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self._to_child, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + self.timeout
        while True:
            m = self._recv(deadline)
            if m.get("id") == self._id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m.get("result", {})
            self.events.append(m)

    def wait_for(self, event, session):
        """Wait for ``event`` from the tab ``session``."""
        if any(e.get("method") == event and e.get("sessionId") == session for e in self.events):
            return
        deadline = time.monotonic() + self.timeout
        while True:
            m = self._recv(deadline)
            self.events.append(m)
            if m.get("method") == event and m.get("sessionId") == session:
                return

    def open(self, url: str):
        """Load ``url`` in a new tab; returns the session id."""
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        self.call("Network.enable", session=session)
        self.call("Page.enable", session=session)
        self.call("Page.navigate", {"url": url}, session=session)
        self.wait_for("Page.loadEventFired", session)
        return session

    def evaluate(self, session, expression):
        res = self.call("Runtime.evaluate", {"expression": expression, "awaitPromise": True,
                                             "returnByValue": True}, session=session)
        if "exceptionDetails" in res:
            raise RuntimeError(f"page script failed: {res['exceptionDetails']}")
        return res["result"].get("value")

    def screenshot(self, session, path: Path):
        data = self.call("Page.captureScreenshot", {"format": "png"}, session=session)["data"]
        path.write_bytes(base64.b64decode(data))

    def requests(self):
        return [e["params"]["request"]["url"] for e in self.events if e.get("method") == "Network.requestWillBeSent"]

    def failures(self):
        return [e["params"] for e in self.events if e.get("method") == "Network.loadingFailed"]

    def close(self):
        self.proc.kill()
        self.proc.wait()
        os.close(self._to_child)
        os.close(self._from_child)
        shutil.rmtree(self.profile, ignore_errors=True)


MATH_STATE = """
(async () => {
  if (window.MathJax && MathJax.startup && MathJax.startup.promise) { await MathJax.startup.promise; }
  return {typeset: document.querySelectorAll('mjx-container').length,
          source: document.querySelectorAll('span.math, div.math').length,
          errors: document.querySelectorAll('mjx-merror').length,
          mathjax: !!(window.MathJax && MathJax.version), version: window.MathJax ? MathJax.version : null};
})()
"""


# Sphinx lists the results one by one and writes its summary ("Search finished, found N pages ...") only at the end:
# wait for the summary, not for the first hit (which may be another page).
SEARCH_HITS = """
(async () => {
  for (let k = 0; k < 300; k++) {
    const summary = document.querySelector('#search-results p.search-summary');
    if (summary && summary.innerText.trim()) {
      return [...document.querySelectorAll('#search-results li a')].map(a => a.getAttribute('href'));
    }
    await new Promise(r => setTimeout(r, 100));
  }
  return ['(search did not finish in 30 s)'];
})()
"""


# ------------------------------------------------------------------------------------------- checker self-tests
def _plant_site(root: Path):
    (root / "sub").mkdir(parents=True)
    (root / "ok.png").write_bytes(b"png")
    (root / "style.css").write_text("/* https://example.org in a comment */ .a{background:url(ok.png)}\n"
                                    ".b{background:url('https://fonts.example.com/x.woff')}")
    (root / "index.html").write_text(
        '<html><head><link rel="stylesheet" href="style.css">'
        '<script src="https://cdn.example.com/mathjax.js"></script></head><body id="top">'
        '<a href="sub/page.html#here">fine</a><a href="sub/page.html#gone">bad anchor</a>'
        '<img src="ok.png"><img src="missing.png"><a href="//example.org/x">proto-relative</a>'
        '<a href="#top">self</a><svg xmlns="http://www.w3.org/2000/svg"></svg></body></html>')
    (root / "sub" / "page.html").write_text('<html><body><h1 id="here">x</h1><a href="../index.html">up</a>'
                                            '<div class="output traceback">Traceback (most recent call last)</div>'
                                            '<script type="application/vnd.jupyter.widget-view+json">{}</script>'
                                            '</body></html>')


def test_site_checker_finds_external_references_and_broken_links(tmp_path):
    _plant_site(tmp_path)
    problems = check_site(tmp_path)
    ext = "\n".join(problems["external"])
    assert "cdn.example.com" in ext and "fonts.example.com" in ext and "//example.org/x" in ext
    assert "w3.org" not in ext and "comment" not in ext  # a namespace and a comment are not loads
    broken = "\n".join(problems["broken"])
    assert "missing.png" in broken and "#gone" in broken
    assert "#here" not in broken and "ok.png" not in broken and "../index.html" not in broken
    assert len(problems["external"]) == 3 and len(problems["broken"]) == 2


def test_rendered_problem_checker_finds_tracebacks_and_widgets(tmp_path):
    _plant_site(tmp_path)
    found = "\n".join(rendered_problems(tmp_path / "sub" / "page.html"))
    assert "error output" in found and "widget" in found
    assert rendered_problems(tmp_path / "index.html") == []
    nb = {"metadata": {"widgets": {}}, "cells": [{"cell_type": "code", "outputs": [
        {"output_type": "error", "ename": "ValueError", "evalue": "x", "traceback": []},
        {"output_type": "display_data", "data": {"application/vnd.jupyter.widget-view+json": {}}}]}]}
    assert len(notebook_problems(nb)) == 3


@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (apt-get install chromium)")
def test_browser_probe_sees_network_requests_missing_files_and_untypeset_math(tmp_path):
    _plant_site(tmp_path)
    (tmp_path / "math.html").write_text('<html><body><span class="math">\\(x^2\\)</span>'
                                        '<script src="https://cdn.example.com/mathjax.js"></script>'
                                        '<img src="missing.png"></body></html>')
    browser = Chromium(CHROMIUM)
    try:
        session = browser.open((tmp_path / "math.html").as_uri())
        state = browser.evaluate(session, MATH_STATE)
    finally:
        browser.close()
    assert state["source"] == 1 and state["typeset"] == 0 and not state["mathjax"]
    assert "https://cdn.example.com/mathjax.js" in browser.requests()
    errors = {f.get("errorText") for f in browser.failures()}
    assert "net::ERR_FILE_NOT_FOUND" in errors and "net::ERR_NAME_NOT_RESOLVED" in errors


def test_a_page_written_again_is_parsed_again(tmp_path):
    """The parse kept for the built book's pages (:func:`parse`) is never a stale one."""
    page = tmp_path / "p.html"
    page.write_text('<a href="a.html">x</a>')
    assert parse(page).refs == [("a", "href", "a.html")]
    page.write_text('<a href="gone.html">x</a><img src="b.png">')
    assert parse(page).refs == [("a", "href", "gone.html"), ("img", "src", "b.png")]
    assert check_site(tmp_path)["broken"] == ["p.html: <a href=gone.html> (no file)", "p.html: <img src=b.png> (no file)"]


def test_untypeset_tex_checker(tmp_path):
    page = tmp_path / "p.html"
    page.write_text('<p>With <span class="math notranslate">\\(\\rho_1\\)</span> fine, costs 5 $ each.</p>'
                    '<pre>x = "$\\alpha$"</pre><div class="output"><pre>\\mu</pre></div>')
    assert untypeset_tex(page) == []
    page.write_text("<p>the terms in $x$ and $$\\ddot x = a\\,x$$ left as text</p>")
    assert len(untypeset_tex(page)) >= 2


def test_clean_notebook_hides_machine_paths_and_keeps_what_a_terminal_shows(tmp_path):
    build = tmp_path / "somewhere" / "build"
    nb = {"metadata": {"papermill": {"input_path": str(build / "x.ipynb"), "output_path": str(build / "y.ipynb"),
                                     "parameters": {"QUICK": True, "OUTPUT_DIR": str(build)}, "duration": 3.2}},
          "nbformat": 4, "nbformat_minor": 5,
          "cells": [{"cell_type": "markdown", "id": "a", "metadata": {}, "source": "# 99 · Title\n"},
                    {"cell_type": "code", "id": "b", "metadata": {"tags": ["injected-parameters"]},
                     "source": f'# Parameters\nQUICK = True\nOUTPUT_DIR = "{build}"\n', "outputs": []},
                    {"cell_type": "code", "id": "c", "metadata": {}, "source": "run()", "outputs": [
                        {"output_type": "stream", "name": "stderr", "text": "\rtrials:   0%|    | 0/4"},
                        {"output_type": "stream", "name": "stderr", "text": "\rtrials:  50%|##  | 2/4"},
                        {"output_type": "stream", "name": "stderr", "text": ["\rtrials: 100%|####| 4/4", "\n"]},
                        {"output_type": "stream", "name": "stdout", "text": ["done\n", "ok\n"]},
                        {"output_type": "stream", "name": "stderr", "text": "\rnext:   0%|    | 0/1"},
                        {"output_type": "stream", "name": "stderr", "text": "\rnext: 100%|####| 1/1\n"}]}]}
    clean = book.clean_notebook(nb, build, source_name="99_title")
    text = json.dumps(clean)
    assert str(tmp_path) not in text
    assert 'OUTPUT_DIR = "<build>"' in clean["cells"][2]["source"]
    outs = clean["cells"][3]["outputs"]
    assert [(o["name"], o["text"]) for o in outs] == [("stderr", "trials: 100%|####| 4/4\n"), ("stdout", "done\nok\n"),
                                                      ("stderr", "next: 100%|####| 1/1\n")]
    note = clean["cells"][1]["source"]
    assert "quick mode" in note and "3 s" in note and "notebooks/99_title.py" in note
    assert nb["cells"][1]["source"].count(str(build)) == 1  # the executed notebook itself is untouched


def test_index_entries_come_from_every_notebooks_opening_cell(tmp_path):
    entries = book.read_entries(tmp_path)
    assert [e.name for e in entries] == [p.stem for p in notebooks.discover()]
    for e in entries:
        assert e.title.startswith(e.name[:2]), f"{e.name}: the opening cell's '# NN · title' heading is missing"
        assert e.sections, f"{e.name}: no '**Paper sections followed.**' paragraph in the opening cell"
        assert e.learn, f"{e.name}: no '**What you will learn.**' paragraph in the opening cell"
        assert not e.executed


def test_status_counts_read_the_last_column():
    md = ("| quantity | paper | reproduced | status |\n|---|---|---|---|\n| a | 1 | 1 | reproduced (tol 1%) |\n"
          "| b | 1 | 2 | differs: printed value not periodic |\n| c | - | 3 | derived |\n| d | 1 | 1 | reproduced |\n")
    assert book._statuses(md) == {"reproduced": 2, "differs": 1, "derived": 1}


def _package_modules() -> set:
    """Every public module of the package, from the files on disk (``cislunar/<wing>/.../<name>.py``)."""
    root = paths.repo_root() / "cislunar"
    found = set()
    for f in root.rglob("*.py"):
        rel = f.relative_to(root.parent).with_suffix("").parts
        if len(rel) >= 3 and not any(part.startswith("_") for part in rel[1:]):
            found.add(".".join(rel))
    return found


def test_api_pages_hold_every_module_once_a_page_per_subpackage(tmp_path):
    """One page per subpackage (one per paper), each module documented exactly once, on its subpackage's page,
    and the API index naming every module and every page."""
    book._write_api_pages(tmp_path)
    modules = _package_modules()
    documented = {}
    for page in sorted(tmp_path.glob("cislunar.*.md")):
        for mod in re.findall(r"^\.\. automodule:: (\S+)$", page.read_text(), flags=re.MULTILINE):
            assert mod not in documented, f"{mod} on {page.name} and {documented[mod]}"
            assert mod.startswith(page.stem + "."), f"{mod} is not in {page.stem}"
            documented[mod] = page.name
    assert set(documented) == modules
    subpackages = {".".join(m.split(".")[:3 if m.split(".")[1] == "papers" else 2]) for m in modules}
    assert {p.stem for p in tmp_path.glob("cislunar.*.md")} == subpackages
    index = (tmp_path / "index.md").read_text()
    assert set(re.findall(r"\{py:mod\}`([^`]+)`", index)) == modules
    toctree = index.split("```{toctree}")[1]
    assert {line.strip() for line in toctree.splitlines()} >= subpackages


def test_book_needs_executed_notebooks(tmp_path):
    with pytest.raises(book.BookError, match="no executed notebooks"):
        book.stage(tmp_path)


# --------------------------------------------------------------------------------------------- the built book
@pytest.fixture(scope="module")
def built(quick_runs):
    """``(build, book_dir, ok_names, seconds)``: a book built from this session's quick runs, or an existing one."""
    existing = os.environ.get("CISLUNAR_BOOK_BUILD")
    if existing:
        build = paths.build_dir(existing)
        out = build / "book"
        if not (out / "index.html").is_file():
            pytest.fail(f"CISLUNAR_BOOK_BUILD={existing}: no book at {out}; run `make book` first")
        ok = sorted(p.stem for p in (build / "notebooks").glob("[0-9][0-9]*_*.ipynb"))
        return build, out, ok, None
    results = quick_runs.all(SOURCES)
    build = quick_runs.build
    marker = quick_runs.root / "book.json"
    with open(quick_runs.root / "book.lock", "a+") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not marker.is_file():
            notebooks.assemble_report(build)
            start = time.perf_counter()
            book.build_book(build, expected=[s.stem for s in SOURCES])
            marker.write_text(json.dumps({"seconds": time.perf_counter() - start}))
    seconds = json.loads(marker.read_text())["seconds"]
    print(f"\nbook built from {len(results)} quick notebooks in {seconds:.1f} s")
    ok = sorted(name for name, r in results.items() if r["ok"])
    return build, build / "book", ok, seconds



@pytest.mark.notebook
@pytest.mark.xdist_group("book")
def test_the_build_is_complete_and_of_one_run(built):
    """What the book was made from: every notebook ran, all in one run, each page and section saying which."""
    build, out, ok, _ = built
    assert provenance.audit_build(build, [s.stem for s in SOURCES]) == []
    run = {r["run_id"] for r in provenance.read_records(build).values()}
    assert len(run) == 1
    (run_id,) = run
    for name in ok:
        assert run_id in (out / "notebooks" / f"{name}.html").read_text(), name
    assert run_id in (out / "report.html").read_text()


def test_the_book_refuses_a_partial_or_mixed_build(tmp_path):
    from cislunar.publish.claims import Claim

    run_a = provenance.new_run(quick=True, seed=0, root=paths.repo_root())
    run_b = provenance.new_run(quick=True, seed=0, root=paths.repo_root())
    build = tmp_path / "b"
    for name, run in (("01_a", run_a), ("02_b", run_b)):
        (build / "notebooks").mkdir(parents=True, exist_ok=True)
        (build / "report").mkdir(exist_ok=True)
        (build / "notebooks" / f"{name}.ipynb").write_text(json.dumps(
            {"cells": [], "metadata": {"cislunar": {"run_id": run.run_id}}, "nbformat": 4, "nbformat_minor": 5}))
        row = Claim("x", kind="derived").judge(1.0)
        (build / "report" / f"{name}.md").write_text(f"## {name}\n\n{provenance.provenance_line(run, 1)}\n\n{row}\n")
        provenance.write_record(build, name, run, status="ok", seconds=1)
    with pytest.raises(provenance.IncompleteBuildError, match="mixed build"):
        book.build_book(build, expected=["01_a", "02_b"])
    with pytest.raises(provenance.IncompleteBuildError, match="03_c: missing"):
        book.build_book(build, expected=["01_a", "03_c"])
    provenance.write_record(build, "01_a", run_a, status="interrupted", seconds=1)
    err = pytest.raises(provenance.IncompleteBuildError, book.build_book, build, expected=["01_a"])
    assert "01_a: interrupted" in str(err.value)
    assert book.main(["--build-dir", str(build)]) == 1


@pytest.mark.notebook
@pytest.mark.xdist_group("book")
def test_a_page_per_notebook_index_report_papers_and_search(built):
    build, out, ok, _ = built
    assert ok, "no notebook executed"
    index = parse(out / "index.html")
    links = {v for _, attr, v in index.refs if attr == "href"}
    for name in ok:
        page = out / "notebooks" / f"{name}.html"
        assert page.is_file(), f"no page for {name}"
        assert f"notebooks/{name}.html" in links, f"the index does not link {name}"
        assert len(page.read_text()) > 5000
    assert sorted(p.stem for p in (out / "notebooks").glob("*.html")) == ok
    text = " ".join(index.text)
    for src in SOURCES:  # every notebook is on the index, executed or not
        assert src.stem[:2] + " ·" in text, src.stem
    for page in ("report.html", "papers.html", "search.html", "searchindex.js", "_static/mathjax/tex-chtml.js"):
        assert (out / page).is_file(), page
    assert any(tag == "form" and v.endswith("search.html") for tag, _, v in index.refs), "no search box"
    report = " ".join(parse(out / "report.html").text)
    assert "Paper versus reproduction" in report and "Mode:" in report
    papers = " ".join(parse(out / "papers.html").text)
    for who in ("Wolf", "Nychka", "Greaves", "Observation and Maneuver Detection for Cislunar Vehicles"):
        assert who in papers
    search = (out / "searchindex.js").read_text()
    assert "Sundman" in search or "CR3BP" in search  # the search index covers the notebooks' text


@pytest.mark.notebook
@pytest.mark.xdist_group("book")
def test_every_local_link_and_image_resolves_and_nothing_is_external(built):
    _, out, _, _ = built
    problems = check_site(out)
    assert problems["external"] == [], "\n".join(problems["external"][:20])
    assert problems["broken"] == [], "\n".join(problems["broken"][:20])
    images = [v for p in (out / "notebooks").glob("*.html") for tag, _, v in parse(p).refs if tag == "img"]
    assert len(images) >= len(list((out / "notebooks").glob("*.html"))), "figures are missing from the pages"


@pytest.mark.notebook
@pytest.mark.xdist_group("book")
def test_every_module_has_its_anchor_and_a_link_from_the_api_index(built):
    """Each module of the package is documented on one API page, under the anchor ``#module-<name>``, and the API
    index links it there."""
    _, out, _, _ = built
    where = {}
    for page in sorted((out / "api").glob("cislunar.*.html")):
        for anchor in parse(page).ids:
            if anchor.startswith("module-"):
                assert anchor not in where, f"{anchor} on {page.name} and {where[anchor]}"
                where[anchor] = page.name
    assert set(where) == {f"module-{m}" for m in _package_modules()}
    links = {v for _, attr, v in parse(out / "api" / "index.html").refs if attr == "href"}
    missing = [f"{page}#{anchor}" for anchor, page in where.items() if f"{page}#{anchor}" not in links]
    assert missing == [], missing


@pytest.mark.notebook
@pytest.mark.xdist_group("book")
def test_api_pages_render_every_docstring_without_markup_errors(built):
    """Docutils renders markup it cannot parse (``|x|`` read as a substitution, a field list ending without a blank
    line) as a red "problematic" span or a system message, and two module docstrings with the same heading give
    one page two sections with the same anchor: none of them on any API page."""
    _, out, _, _ = built
    problems = []
    for page in sorted((out / "api").glob("*.html")):
        text = page.read_text()
        problems += [f"{page.name}: {n} x {what}" for what in ('class="problematic"', 'class="system-message"')
                     if (n := text.count(what))]
        ids = re.findall(r'\sid="([^"]+)"', text)
        problems += [f"{page.name}: anchor {i!r} {ids.count(i)} times" for i in sorted(set(ids)) if ids.count(i) > 1]
    assert problems == [], "\n".join(problems[:30])


@pytest.mark.notebook
@pytest.mark.xdist_group("book")
def test_no_error_or_widget_output_is_rendered(built):
    build, out, ok, _ = built
    problems = []
    for name in ok:
        problems += [f"{name}.ipynb: {p}" for p in
                     notebook_problems(json.loads((build / "notebooks" / f"{name}.ipynb").read_text()))]
    for page in sorted(out.rglob("*.html")):
        problems += [f"{page.relative_to(out)}: {p}" for p in rendered_problems(page)]
    assert problems == [], "\n".join(problems[:30])


@pytest.mark.notebook
@pytest.mark.xdist_group("book")
def test_markdown_math_is_parsed_on_every_page(built):
    """No TeX command or dollar delimiter is left in the running text (e.g. a "$$...$$" the parser missed)."""
    _, out, _, _ = built
    problems = [f"{p.relative_to(out)}: {hit!r}" for p in sorted(out.rglob("*.html")) for hit in untypeset_tex(p)]
    assert problems == [], "\n".join(problems[:30])


@pytest.mark.notebook
@pytest.mark.xdist_group("book")
def test_no_page_shows_a_machine_path(built):
    """Parameters cells and outputs show no absolute path of this machine (e.g. a printed save_figure result)."""
    build, out, _, _ = built
    private = {str(paths.repo_root().resolve()), str(build.resolve()), tempfile.gettempdir().rstrip("/") + "/"}
    problems = []
    for page in sorted(out.rglob("*.html")):
        text = "".join(parse(page).text)
        for s in sorted(private, key=len, reverse=True):
            at = text.find(s)
            if at >= 0:
                problems.append(f"{page.relative_to(out)}: {text[max(0, at - 60):at + 80]!r}")
                break
    assert problems == [], "pages show machine paths:\n" + "\n".join(problems[:30])


@pytest.mark.notebook
@pytest.mark.xdist_group("book")
@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (apt-get install chromium)")
def test_headless_chromium_typesets_math_offline(built):
    """Every notebook page, the index and the report load with the network cut off and MathJax typesets all
    their math without errors; a screenshot of the page with the most math is kept next to the book; the search
    box finds that page."""
    build, out, ok, _ = built
    notebook_pages = sorted(out.glob("notebooks/*.html"), key=lambda p: -p.read_text().count('class="math'))
    page = notebook_pages[0]
    states = {}
    browser = Chromium(CHROMIUM)
    try:
        for other in [*notebook_pages[1:], out / "index.html", out / "report.html"]:
            states[other.relative_to(out).as_posix()] = browser.evaluate(browser.open(other.resolve().as_uri()),
                                                                          MATH_STATE)
        session = browser.open(page.resolve().as_uri())
        state = states[page.relative_to(out).as_posix()] = browser.evaluate(session, MATH_STATE)
        browser.evaluate(session, "(() => { const m = document.querySelector('mjx-container[display=\"true\"]') "
                                  "|| document.querySelector('mjx-container'); "
                                  "if (m) { m.scrollIntoView({block: 'center'}); } return !!m; })()")
        shot = build / f"book-screenshot-{page.stem}.png"
        browser.screenshot(session, shot)
        page_failures = browser.failures()  # the search page's snippet fetches fail on file:// by design
        title = " ".join(parse(page).text).split("—")[0]
        word = max(re.findall(r"[A-Za-z]{5,}", title), key=len)
        search = browser.open((out / "search.html").resolve().as_uri() + f"?q={word}")
        hits = browser.evaluate(search, SEARCH_HITS)
    finally:
        browser.close()
    print(f"\nscreenshot of {page.name}: {shot}; MathJax {state['version']}: {state['typeset']} of "
          f"{state['source']} formulas typeset; {sum(s['typeset'] for s in states.values())} formulas on "
          f"{len(states)} pages")
    assert state["source"] > 0, f"{page.name} has no math"
    for name, st in states.items():
        if st["source"]:
            assert st["mathjax"], f"{name}: MathJax did not load"
        assert st["typeset"] >= st["source"], f"{name}: {st}"
        assert st["errors"] == 0, f"{name}: {st['errors']} formulas failed to typeset (TeX errors)"
    outside = [u for u in browser.requests() if not u.startswith(("file:", "data:", "blob:", "about:"))]
    assert outside == [], f"the pages asked the network for {outside}"
    failed = [f"{f.get('type')}: {f.get('errorText')}" for f in page_failures]
    assert failed == [], failed
    assert shot.stat().st_size > 20000
    assert any(h.split("#")[0].endswith(f"notebooks/{page.name}") for h in hits), \
        f"the search box does not find {page.name} for {word!r}: {hits}"

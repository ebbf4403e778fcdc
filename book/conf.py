"""Sphinx configuration of the cislunar book (built by ``python -m cislunar.publish.book``; see ``cislunar/book.py``).

The book is assembled from already executed notebooks: nothing is executed here (``nb_execution_mode = "off"``).
Everything a page needs is served from the build itself, so the book reads offline: MathJax comes from the Python
package ``sphinx-mathjax-offline`` (copied into ``_static/mathjax``), no widget JavaScript, no external links in the
theme.
"""

import os

project = "cislunar: a literate reproduction of four cislunar navigation and tracking papers"
author = "the cislunar contributors"
copyright = "the cislunar contributors"
release = os.environ.get("CISLUNAR_BOOK_RELEASE", "")

extensions = [
    "myst_nb",
    "sphinx.ext.mathjax",
    "sphinx.ext.autodoc",  # the API reference pages (api/), from the package's docstrings
    "sphinx.ext.napoleon",  # which are numpydoc
]
napoleon_google_docstring = False
napoleon_numpy_docstring = True
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the docstrings state types with units
# Documented functions and classes are not entries of the table of contents (the API pages list their modules).
# Sphinx copies every page's table of contents into the navigation of every page; with an entry per object
# (about 2300) that copying was a third of the build.  Objects keep their anchors, index and search entries.
toc_object_entries = False

# Notebooks are executed by cislunar.publish.notebooks (papermill); the book only renders them.
nb_execution_mode = "off"
nb_merge_streams = False  # cislunar.publish.book merges consecutive writes itself, keeping the order of outputs
nb_output_stderr = "show"  # shown, but styled as plain output (book/_static/cislunar-book.css)
nb_render_markdown_format = "myst"  # the closing comparison tables are Markdown outputs, with math
nb_ipywidgets_js = {}  # never load widget renderers from the internet
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence"]
myst_heading_anchors = 3
myst_dmath_double_inline = True  # "$$...$$" inside a paragraph, as Jupyter renders it
# "ref.python": a word of a numpydoc type field ("n", "orbit", "time") that names attributes of several classes
# is an ambiguous cross-reference; it stays plain text, and the warning (about 130 per build) is noise.
suppress_warnings = ["myst.header", "mystnb.unknown_mime_type", "ref.python"]

# MathJax 3 from a Python package, never a CDN.  The files are copied into _static/mathjax after the build.
mathjax_path = "mathjax/tex-chtml.js"
mathjax3_config = {
    "tex": {"inlineMath": [["\\(", "\\)"]], "displayMath": [["\\[", "\\]"]]},
    "options": {"enableMenu": False},
}

exclude_patterns = ["_build", "**.ipynb_checkpoints"]
source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb"}

html_theme = "sphinx_book_theme"
html_title = "cislunar reproduction"
html_static_path = ["_static"]
html_css_files = ["cislunar-book.css"]
html_show_sphinx = False
html_show_sourcelink = False
html_copy_source = False
html_last_updated_fmt = None
html_theme_options = {
    "home_page_in_toc": True,
    "show_navbar_depth": 1,
    "use_download_button": False,
    "use_fullscreen_button": False,
    "use_repository_button": False,
    "use_source_button": False,
    "use_edit_page_button": False,
    "use_issues_button": False,
    "launch_buttons": {},
    "footer_content_items": [],
    "extra_footer": "",
    "show_toc_level": 2,
}
html_context = {"default_mode": "light"}

"""The command-line processes import only what they use.

The notebook runner starts one child process per notebook and each reads notebooks with jupytext; the top-level
package therefore resolves ``cislunar.CR3BP`` / ``cislunar.EARTH_MOON`` on first use (PEP 562) instead of importing
the dynamics (and with it ``scipy.optimize``) on ``import cislunar``.
"""

import subprocess
import sys
import textwrap

import pytest


def _run(code: str) -> str:
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


def test_importing_the_runner_does_not_import_scipy_or_the_dynamics():
    assert _run("""
        import sys
        import cislunar.publish.notebooks
        print(sorted(m for m in ("scipy", "cislunar.cr3bp.dynamics", "jupytext", "papermill") if m in sys.modules))
    """) == "[]"


def test_the_top_level_names_resolve_on_first_use_to_the_dynamics_objects():
    import cislunar
    from cislunar.cr3bp import dynamics

    assert cislunar.EARTH_MOON is dynamics.EARTH_MOON
    assert cislunar.CR3BP is dynamics.CR3BP
    from cislunar import EARTH_MOON  # the from-import form goes through the same hook

    assert EARTH_MOON is dynamics.EARTH_MOON
    assert {"CR3BP", "EARTH_MOON"} <= set(dir(cislunar))


def test_an_unknown_top_level_name_is_an_attribute_error_naming_it():
    import cislunar

    with pytest.raises(AttributeError, match="no_such_name"):
        cislunar.no_such_name  # noqa: B018
    assert not hasattr(cislunar, "no_such_name")


def test_the_runner_command_reads_notebooks_without_the_iri_grammar():
    # main() marks rfc3987_syntax absent before anything reads a notebook (its grammar costs 0.8-2 s at import)
    assert _run("""
        import sys
        from cislunar.publish import notebooks
        assert notebooks.main(["no-such-notebook"]) == 2  # refused before any notebook is read
        print(sys.modules.get("rfc3987_syntax", "absent"))
    """) == "None"

"""Docstrings hold no control characters: a ``\\rho`` or ``\\beta`` in a non-raw string is a carriage return or
a backspace, which the API pages of the book render as garbage."""

from __future__ import annotations

import ast
from pathlib import Path

import cislunar

CONTROL = "\r\x07\x08\x0b\x0c"


def test_no_control_characters_in_string_literals():
    found = []
    for path in sorted(Path(cislunar.__file__).parent.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and len(node.value) > 3 \
                    and any(c in node.value for c in CONTROL):
                found.append(f"{path.name}:{node.lineno}")
    assert not found, f"control characters (an unescaped \\r, \\b, \\f, \\a or \\v?) in strings at {found}"

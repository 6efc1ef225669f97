"""Docstrings and comments say what the code does, in the present tense.

Timings, cache and memory sizes of a run, hosts, dates and designs tried and
dropped belong in ``docs/performance.md``, not in the code (issue 70). This
test reads every comment and every string statement (module, class and
function docstrings, and the strings documenting a constant) of the modules
under ``COVERED`` and fails on a line that holds a timing, host or date word.

``COVERED`` lists what has been rewritten so far; widen it to ``("dlasweep",)``
once the rest of the package is. ``ALLOWED`` holds the few hits that are not a
measurement (a unit in a formula, a value the code itself sets), each with the
exact text it permits, so that a new hit in the same place still fails.
"""

import ast
import io
import re
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

COVERED = ("dlasweep/kernels", "dlasweep/_jit.py")
"""Folders (and single modules) whose docstrings and comments the test reads, relative to the repository."""

PATTERNS = {
    "nanoseconds": r"\bns\b",
    "mebibytes": r"\bMiB\b",
    "gibibytes": r"\bGiB\b",
    "megabytes": r"\bMB\b",
    "gigabytes": r"\bGB\b",
    "measured": r"(?i)\bmeasured\b",
    "not kept": r"(?i)\bnot kept\b",
    "this host": r"(?i)\bthis host\b",
    "host": r"(?i)\bhosts?\b",
    "a year": r"\b20\d\d\b",
    "a duration": r"\d+(\.\d+)? ?(s|us|ms|µs)\b",
    "cycles": r"(?i)\bcycles\b",
    "a percentage": r"%",
}
"""The words of a lab notebook: a timing, a size of a run, a host, a date, a rejected design."""

ALLOWED = {
    # (module, the text of the line, stripped): why it is not a measurement
    ("dlasweep/kernels/maps.py", "Bytes from which ``zeroed`` maps its array with ``_unreserved`` (256 MiB: a 3D"):
        "the constant's own value, 2**28 bytes, in a unit a reader knows",
}


def _modules():
    for entry in COVERED:
        path = ROOT / entry
        yield from sorted(path.rglob("*.py")) if path.is_dir() else [path]


def texts(source):
    """(line number, text) of every comment and every line of every string statement of ``source``."""
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type == tokenize.COMMENT:
            yield token.start[0], token.string
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
            for k, line in enumerate(node.value.value.split("\n")):
                yield node.value.lineno + k, line


def hits(source, module):
    """Every (line number, pattern name, text) of ``source`` that a pattern matches and ``ALLOWED`` does not."""
    found = []
    for line, text in texts(source):
        if (module, text.strip()) in ALLOWED:
            continue
        for name, pattern in PATTERNS.items():
            if re.search(pattern, text):
                found.append((line, name, text.strip()))
    return sorted(found)


def test_the_covered_modules_exist():
    assert all((ROOT / entry).exists() for entry in COVERED)
    assert len(list(_modules())) > 10


@pytest.mark.parametrize("path", list(_modules()), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_lab_notebook_in_docstrings_or_comments(path):
    module = str(path.relative_to(ROOT))
    found = hits(path.read_text(), module)
    assert not found, f"{module}: timings, hosts or dates belong in docs/performance.md:\n" + "\n".join(
        f"  line {line} ({name}): {text}" for line, name, text in found)


def test_every_allowance_is_still_used():
    """An allowance whose line is gone is dropped, so that the list stays the few hits there are."""
    for module, text in ALLOWED:
        lines = [t.strip() for _, t in texts((ROOT / module).read_text())]
        assert text in lines, (module, text)


@pytest.mark.parametrize("text, name", [
    ("# 2D 1e6 took 5.97 s against 6.45", "a duration"),
    ("a read costs 17 ns on this host", "nanoseconds"),
    ("the field spans 5.5 MiB at 1e7", "mebibytes"),
    ("Measured and not kept: ...", "measured"),
    ("since 2026-11-27", "a year"),
    ("1.9k cycles a particle", "cycles"),
    ("it made the growth 44% slower", "a percentage"),
    ("14 us a generator", "a duration"),
])
def test_the_patterns_catch_a_notebook_line(text, name):
    source = f'"""{text}"""\n' if not text.startswith("#") else text + "\n"
    assert name in {n for _, n, _ in hits(source, "example.py")}


def test_the_patterns_pass_a_plain_docstring():
    source = '"""Lower bound on the distance from X to every particle, in sites (see docs/performance.md)."""\n'
    assert hits(source, "example.py") == []

"""Docstrings and comments say what the code does, in the present tense.

Timings, cache and memory sizes of a run, hosts, dates and designs tried and
dropped belong in ``docs/performance.md``, not in the code (issue 70). This
test reads every comment and every string statement (module, class and
function docstrings, and the strings documenting a constant) of the modules
under ``COVERED`` and fails on a line that holds a timing, host or date word.

``COVERED`` is the whole package. ``ALLOWED`` holds the few hits that are not a
measurement (a unit in a formula, a value the code itself sets), each with the
exact text it permits, so that a new hit in the same place still fails.
``ALLOWED_WORDS`` lets one folder use a word as the subject of its code (the
benchmark reads its host's memory), each with its reason.
"""

import ast
import io
import re
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

COVERED = ("dlasweep",)
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
    # a number, a space and s; or a number and us, ms or µs: "2s" is a box side (measures.boxes), not a time
    "a duration": r"\d+(\.\d+)? (s|us|ms|µs)\b|\d+(\.\d+)?(us|ms|µs)\b",
    "cycles": r"(?i)\bcycles\b",
    # a number and %, but the confidence level (95%, stats.constants.CONFIDENCE) is not a measurement
    "a percentage": r"(?<![\d.])(?!95%)\d+(\.\d+)?%",
}
"""The words of a lab notebook: a timing, a size of a run, a host, a date, a rejected design."""

ALLOWED = {
    # (module, the text of the line, stripped): why it is not a measurement
    ("dlasweep/kernels/maps.py", "Bytes from which ``zeroed`` maps its array with ``_unreserved`` (256 MiB: a 3D"):
        "the constant's own value, 2**28 bytes, in a unit a reader knows",
    ("dlasweep/measures/boxes.py", "Most bits (256 MiB) a stack of bitmaps (a side's grids, or its strips) may take; "
     "a grid larger than this"): "the constant's own value, 2**31 bits",
    ("dlasweep/measures/boxes.py", "Most bytes (512 MiB) of a prefix's shifted, first-axis ordered copy that the "
     "marking takes at a time"): "the constant's own value, 2**29 bytes",
    ("dlasweep/bench/benchmark.py", "A sweep process should take at most 1.25 x ideal + 2 s (interpreter, imports, "
     "embedded cluster)."): "the target's own value (RATIO_TARGET)",
    ("dlasweep/bench/benchmark.py", '"met", or by how much ``seconds`` is over ``target``, never "over by 0.00 s".'):
        "the text the function never prints",
    ("dlasweep/bench/targets.py", "Steps per particle may grow at most like log N: from 1e5 to 1e7 by at most 40%."):
        "the target's own value (STEPS_GROWTH_TARGET = 1.40)",
    ("dlasweep/bench/targets.py", '# under 1%, one decimal: "0% over" would read as met'):
        "the format the code chooses, and the text it avoids",
    ("dlasweep/reporting/readout.py", "D of DLA: 2D off-lattice 1.7100(3) (Menshutin et al. 2008); 3D about 2.50."):
        "the year of a citation",
    ("dlasweep/sweep/plan.py", "Bytes as a user reads them: ``1.2 GB``."): "an example of the function's output",
    ("dlasweep/sweep/progress.py", "``42 s``, ``12 min``, ``3.5 h``."): "examples of the function's output",
    ("dlasweep/sweep/runner.py", "bar on a terminal, else a line each 10% of the clusters or 10 s"):
        "progress.Lines' own defaults (fraction=0.1, seconds=10.0)",
    ("dlasweep/stats/summary.py", "widest flat window between the end of the transient (5% of N) and N"):
        "the code's own value (constants.START_FRACTION = 0.05)",
}

ALLOWED_WORDS = {
    # (folder, pattern name): why the folder's code has this word for its subject
    ("dlasweep/bench", "host"): "the benchmark reads and reports its host's memory (bench.host); the word names "
                                "what the code probes, not where a figure was taken",
    ("dlasweep/bench", "nanoseconds"): "the unit of the host probe's results and of the bench's ns/step column",
    ("dlasweep/bench", "mebibytes"): "the unit of the probe's working sets and of the bench's memory variables",
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
            if any(module.startswith(folder + "/") and name == word for folder, word in ALLOWED_WORDS):
                continue
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
    ("listed once a batch: 15 s for 1e7 clusters", "a duration"),
    ("scanned it at about 70 ms each", "a duration"),
    ("covered 71%, 78%, 86%", "a percentage"),
    ("it covers the true D in 95.0%, 93.8%", "a percentage"),
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


@pytest.mark.parametrize("text", [
    "Lower bound on the distance from X to every particle, in sites (see docs/performance.md).",
    "The box of side 2s at offset o is the union of 2**dim boxes of the grid of side s at offset o % s.",
    "Headline D, its 95% CI, local slopes.",
])
def test_the_patterns_pass_a_plain_docstring(text):
    assert hits(f'"""{text}"""\n', "example.py") == []


def test_a_word_allowed_in_one_folder_is_caught_elsewhere():
    source = '"""The host\'s reads, in ns."""\n'
    assert hits(source, "dlasweep/bench/host.py") == []
    assert {name for _, name, _ in hits(source, "dlasweep/sweep/plan.py")} == {"host", "nanoseconds"}

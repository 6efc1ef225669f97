"""The statistical constants are stated once, in dlasweep/stats/constants.py: the words say the confidence level
from it."""

import ast

from conftest import ROOT
from dlasweep.stats.constants import CONFIDENCE, LEVEL


def test_the_level_in_words_is_the_confidence_level():
    assert LEVEL == f"{round(100 * CONFIDENCE)}%"


def test_no_label_or_message_spells_the_level_itself():
    """Docstrings may say 95%; a string the user reads (a label, a long name, a reason) takes ``LEVEL``."""
    spelled = []
    for path in (ROOT / "dlasweep").rglob("*.py"):
        tree = ast.parse(path.read_text())
        docstrings = {id(node.value) for node in ast.walk(tree)
                      if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)}
        spelled += [f"{path.relative_to(ROOT)}:{node.lineno}" for node in ast.walk(tree)
                    if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings
                    and f"{LEVEL}" in node.value]
    assert spelled == []

"""The README's tour of the package ("Where things are") names every subpackage, docs/architecture.md every
module, and every path either names exists."""

import re

from conftest import ROOT

PACKAGE = ROOT / "dlasweep"


def tour() -> str:
    text = (ROOT / "README.md").read_text()
    start = text.index("## Where things are")
    end = text.find("\n## ", start + 1)
    return text[start:] if end < 0 else text[start:end]


def architecture() -> str:
    return (ROOT / "docs" / "architecture.md").read_text()


def test_the_tour_names_every_subpackage():
    subpackages = [p for p in PACKAGE.iterdir() if (p / "__init__.py").exists()]
    assert len(subpackages) >= 8
    missing = [p.name for p in subpackages if f"dlasweep/{p.name}/" not in tour()]
    assert missing == [], f"not in the README's tour: {missing}"


def test_the_architecture_names_every_module():
    named = architecture()
    modules = [p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts
               and (p.name != "__init__.py" or p.parent == PACKAGE)]
    assert len(modules) > 30
    missing = [str(p.relative_to(ROOT)) for p in modules if str(p.relative_to(ROOT)) not in named]
    assert missing == [], f"not in docs/architecture.md: {missing}"


def test_every_path_they_name_exists():
    paths = [path for text in (tour(), architecture())
             for path in re.findall(r"\b((?:dlasweep|tests|workflows|results|docs)/[\w/]*(?:\.py|\.md)?)", text)]
    assert len(paths) > 40
    missing = [path for path in paths if not (ROOT / path).exists()]
    assert missing == []

"""The README's tour of the package ("Where things are") names every module, and only modules there are."""

import re

from conftest import ROOT


def tour() -> str:
    text = (ROOT / "README.md").read_text()
    return text[text.index("## Where things are"):]


def test_the_tour_names_every_module():
    named = tour()
    package = ROOT / "dlasweep"
    modules = [p for p in package.rglob("*.py") if p.name != "__init__.py" and "__pycache__" not in p.parts]
    assert len(modules) > 30
    missing = [str(p.relative_to(ROOT)) for p in modules
               if f"dlasweep/{p.relative_to(package).as_posix()}" not in named and f" {p.name}" not in named]
    assert missing == [], f"not in the README's tour: {missing}"


def test_every_path_the_tour_names_exists():
    for path in re.findall(r"\b((?:dlasweep|tests|workflows|results)/[\w/]*(?:\.py)?)", tour()):
        assert (ROOT / path).exists(), path

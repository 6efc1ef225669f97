"""The front door: the licence, the citation, the changelog and the declared dependencies.

These read files and the package's source text only (no package module is imported but
``dlasweep._version``), so they hold whatever the layout of the modules.
"""

import ast
import json
import re
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PYPROJECT = ROOT / "pyproject.toml"

# Import names whose distribution on PyPI is spelled otherwise (compared after PEP 503 normalisation).
DISTRIBUTION = {"yaml": "pyyaml", "dask_jobqueue": "dask-jobqueue", "sklearn": "scikit-learn", "PIL": "pillow"}
# Extras that the package itself does not use: what they bring is not a declaration of the package's imports.
NOT_RUNTIME = {"test", "docs"}


def _version():
    text = (ROOT / "dlasweep" / "_version.py").read_text()
    return re.search(r'^__version__ = "([^"]+)"', text, re.M).group(1)


def _normal(name):
    return re.sub(r"[-_.]+", "-", name).lower()


def declared(project):
    """The distributions a [project] table declares for the package at run time: its dependencies and the
    extras other than test and docs, each with the extras it asks for (``dask[distributed]`` declares
    ``distributed`` too)."""
    reqs = list(project.get("dependencies", []))
    for extra, more in project.get("optional-dependencies", {}).items():
        if extra not in NOT_RUNTIME:
            reqs += more
    names = set()
    for req in reqs:
        m = re.match(r"\s*([A-Za-z0-9][A-Za-z0-9._-]*)\s*(?:\[([^\]]*)\])?", req)
        names.add(_normal(m.group(1)))
        names.update(_normal(e) for e in (m.group(2) or "").split(",") if e.strip())
    return names


def imported(package_dir):
    """{top-level name: first file importing it} of every absolute import of a third-party module under
    ``package_dir`` (at any depth of the file: the lazy imports inside functions count)."""
    found = {}
    for path in sorted(package_dir.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.split(".")[0]
                if top not in sys.stdlib_module_names and top != "__future__" and top != package_dir.name:
                    found.setdefault(top, path.relative_to(package_dir.parent).as_posix())
    return found


def undeclared(project, package_dir):
    """The third-party imports of the package that ``project`` does not declare, with a file importing each."""
    names = declared(project)
    return {top: where for top, where in imported(package_dir).items()
            if _normal(DISTRIBUTION.get(top, top)) not in names}


def test_every_imported_package_is_declared():
    project = tomllib.loads(PYPROJECT.read_text())["project"]
    assert imported(ROOT / "dlasweep"), "no third-party import found: the scan reads nothing"
    missing = undeclared(project, ROOT / "dlasweep")
    assert not missing, f"imported but not declared in pyproject.toml: {missing}"


def test_an_undeclared_import_is_found(tmp_path):
    """The check itself: a package importing psutil, yaml and a lazy netCDF4 against dependencies that
    declare only netCDF4 names psutil and yaml (by their import names)."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("import os\nimport psutil\nfrom . import sub\n")
    (pkg / "sub.py").write_text("def f():\n    import netCDF4\n    from yaml import safe_load\n")
    missing = undeclared({"dependencies": ["netCDF4>=1.6"], "optional-dependencies": {"test": ["pyyaml"]}}, pkg)
    assert set(missing) == {"psutil", "yaml"}


def test_licence():
    text = (ROOT / "LICENSE").read_text()
    assert "BSD 3-Clause License" in text and "Copyright (c) 2026, The dlasweep developers" in text
    project = tomllib.loads(PYPROJECT.read_text())["project"]
    assert project["license"] == "BSD-3-Clause"
    assert "LICENSE" in project["license-files"]
    assert "License :: " not in " ".join(project.get("classifiers", [])), \
        "an SPDX license field and a License classifier together are refused by setuptools"


def test_citation_is_valid_cff_1_2_0():
    """CITATION.cff against the CFF 1.2.0 JSON schema (tests/cff_schema_1.2.0.json, the schema that
    cffconvert 2.0.0 ships, CC-BY-4.0 by the Citation File Format authors), and its version the package's."""
    yaml = pytest.importorskip("yaml")
    jsonschema = pytest.importorskip("jsonschema")
    schema = json.loads((ROOT / "tests" / "cff_schema_1.2.0.json").read_text())
    # YAML reads an unquoted date as a date; CFF's schema wants its text
    cff = json.loads(json.dumps(yaml.safe_load((ROOT / "CITATION.cff").read_text()), default=str))
    jsonschema.Draft7Validator(schema, format_checker=jsonschema.FormatChecker()).validate(cff)
    assert cff["cff-version"] == "1.2.0"
    assert str(cff["version"]) == _version()
    project = tomllib.loads(PYPROJECT.read_text())["project"]
    assert cff["license"] == project["license"]


def test_citation_schema_rejects(tmp_path):
    """The schema check can fail: a citation without authors, or with a made-up licence, is refused."""
    yaml = pytest.importorskip("yaml")
    jsonschema = pytest.importorskip("jsonschema")
    schema = json.loads((ROOT / "tests" / "cff_schema_1.2.0.json").read_text())
    cff = json.loads(json.dumps(yaml.safe_load((ROOT / "CITATION.cff").read_text()), default=str))
    validator = jsonschema.Draft7Validator(schema)
    assert validator.is_valid(cff)
    assert not validator.is_valid({k: v for k, v in cff.items() if k != "authors"})
    assert not validator.is_valid({**cff, "license": "BSD-4-Clause-Whatever"})


def released_versions(text):
    """The released versions of a Keep a Changelog file, newest first (``## [x.y.z] - YYYY-MM-DD``)."""
    return re.findall(r"^## \[(\d+\.\d+\.\d+[^\]]*)\] - \d{4}-\d{2}-\d{2}\s*$", text, re.M)


def test_changelog_top_version_is_the_package_version():
    text = (ROOT / "CHANGELOG.md").read_text()
    assert text.startswith("# Changelog")
    assert "## [Unreleased]" in text
    versions = released_versions(text)
    assert versions, "no released version in CHANGELOG.md"
    assert versions[0] == _version(), f"CHANGELOG.md's top version {versions[0]}, dlasweep {_version()}"


def test_version_is_the_installed_one():
    """The package's ``__version__`` and the version its metadata says, where it is installed from here."""
    import dlasweep

    assert dlasweep.__version__ == _version()


README_LINES = 150
"""A README a newcomer reads in five minutes; the long sections live in docs/."""


def readme_problems(text):
    """What keeps ``text`` from being the README: too long, a tracker's number, a date, no picture first,
    a link to a file that is not there."""
    lines = text.splitlines()
    problems = [f"{len(lines)} lines, more than {README_LINES}"] if len(lines) > README_LINES else []
    problems += [f"names the tracker: {m.group(0)!r}" for m in re.finditer(r"\b[Ii]ssues? #?\d+", text)]
    problems += [f"a date: {m.group(0)!r}" for m in re.finditer(r"\b20\d\d-\d\d-\d\d\b", text)]
    pictures = [i for i, line in enumerate(lines) if line.startswith("![")]
    if not pictures or pictures[0] > 5:
        problems.append("no picture at the top")
    for target in re.findall(r"\]\(([^)#]+)\)", text):
        if not target.startswith("http") and not (ROOT / target).exists():
            problems.append(f"links to {target}, which is not there")
    return problems


def test_the_readme_is_short_and_points_into_the_docs():
    text = (ROOT / "README.md").read_text()
    assert readme_problems(text) == []
    for page in ("getting-started", "model", "spec", "dataset", "measuring-d", "clusters", "pictures", "api"):
        assert f"(docs/{page}.md)" in text, page
    for command in ("pip install .", "environment.yml", "make sweep", "make test", "dlasweep init"):
        assert command in text, command


def test_the_readme_check_finds_what_it_is_for():
    good = (ROOT / "README.md").read_text()
    assert readme_problems(good + "\n" * README_LINES) == [f"{len(good.splitlines()) + README_LINES} lines, "
                                                           f"more than {README_LINES}"]
    assert readme_problems(good.replace("## Install", "## Install (issue 71, 2026-12-07)")) == [
        "names the tracker: 'issue 71'", "a date: '2026-12-07'"]
    assert readme_problems(good.replace("![", "[", 1)) == ["no picture at the top"]
    assert readme_problems(good + "[gone](docs/gone.md)\n") == ["links to docs/gone.md, which is not there"]

"""The documentation site builds clean: every warning an error, every reference checked (nitpicky).

The build runs the lesson notebook (myst-nb, at the small n that docs/_ext/tables.py gives it) and makes
the tables of the model, the spec and the dataset from the package's own tables; the test then reads the
built pages for every name of those tables, so a table that stops being generated, or a page that loses
one, fails here as well as a broken reference does.
"""

from __future__ import annotations

import html
import re
import subprocess
import sys

import pytest

from conftest import ROOT

pytest.importorskip("sphinx")
pytest.importorskip("myst_nb")
pytest.importorskip("pydata_sphinx_theme")
pytest.importorskip("numpydoc")

DOCS = ROOT / "docs"
sys.path.insert(0, str(DOCS / "_ext"))
import tables  # noqa: E402  (docs/_ext/tables.py: where the package's tables are, on either side of a move)


def _text(page):
    """A built page's text, tags removed, entities decoded and Sphinx's curly quotes made straight again."""
    text = html.unescape(re.sub(r"<[^>]+>", " ", page.read_text()))
    return text.translate(str.maketrans("\u2018\u2019\u201c\u201d", "''\"\""))


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("docs")
    run = subprocess.run([sys.executable, "-m", "sphinx", "-b", "html", "-W", "--keep-going", "-n", "-q",
                          "-d", str(out / "doctrees"), str(DOCS), str(out / "html")],
                         capture_output=True, text=True, cwd=ROOT)
    # Sphinx's own "WARNING: ..." and "ERROR: ..." (the lesson's kernel logs "WARNING | ..." of its own)
    warnings = [line for line in run.stderr.splitlines() if re.search(r"\b(WARNING|ERROR|CRITICAL):", line)]
    assert run.returncode == 0 and not warnings, "the docs build warned or failed:\n" + run.stderr[-6000:]
    return out / "html"


@pytest.mark.slow
def test_the_pages_are_built(site):
    for page in ("index", "getting-started", "model", "spec", "dataset", "measuring-d", "clusters", "pictures",
                 "benchmark", "gallery", "api", "architecture", "performance", "_generated/lesson",
                 "api/generated/dlasweep.grow", "api/generated/dlasweep.Cluster"):
        assert (site / f"{page}.html").is_file(), page


@pytest.mark.slow
def test_the_model_table_is_the_parameter_table(site):
    params = tables._module("dlasweep.growth.params", "dlasweep.params")
    text = _text(site / "model.html")
    for name, par in params.PARAMETERS.items():
        assert name in text and " ".join(par.meaning.split()) in " ".join(text.split()), name


@pytest.mark.slow
def test_the_spec_page_names_every_key(site):
    spec = tables._module("dlasweep.sweep.spec", "dlasweep.spec")
    params = tables._module("dlasweep.growth.params", "dlasweep.params")
    text = _text(site / "spec.html")
    for key in (*spec._TOP_KEYS, *spec._GRID_KEYS, *spec._RUN_KEYS, *params.PARAMETERS):
        assert re.search(rf"\b{key}\b", text), key


@pytest.mark.slow
def test_the_dataset_page_names_every_variable(site):
    schema = tables._module("dlasweep.data.schema", "dlasweep.schema")
    params = tables._module("dlasweep.growth.params", "dlasweep.params")
    text = " ".join(_text(site / "dataset.html").split())
    for name, var in schema.SCHEMA.items():
        if name not in params.PARAMETERS:  # the parameters are the model page's table
            assert re.search(rf"\b{name}\b", text) and " ".join(var.long_name.replace("`", "").split()) in text, name


@pytest.mark.slow
def test_the_lesson_ran(site):
    page = (site / "_generated" / "lesson.html").read_text()
    assert f"grew the lattice cluster: {tables.LESSON_N} particles" in page
    assert len(re.findall(r'<img [^>]*src="[^"]*\.png"', page)) >= 3  # the two clusters and the plot, drawn


def test_an_undescribed_spec_key_fails_the_build(monkeypatch):
    """The spec table refuses to build when the spec has a key the docs do not describe."""
    from sphinx.errors import ExtensionError

    monkeypatch.delitem(tables.SPEC_KEYS, ("run", "workers"))
    with pytest.raises(ExtensionError, match="workers"):
        tables.spec_keys_md()

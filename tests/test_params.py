"""The parameter table is the one source: resolve, the docs and the package's public names follow it."""

import re

import pytest

import dlasweep as dla
from conftest import ROOT
from dlasweep.params import DEFAULTS, PARAMETERS, markdown_table, resolve


def test_the_docs_table_of_the_model_is_made_from_the_table():
    # docs/model.md includes the table docs/_ext/tables.py writes from PARAMETERS at every build (tests/test_docs.py
    # reads the built page); markdown_table() is the same table in plain text, a row per parameter.
    assert "_generated/parameters.md" in (ROOT / "docs" / "model.md").read_text()
    rows = markdown_table().splitlines()[2:]
    assert [row.split(" | ")[0].removeprefix("| ") for row in rows] == list(PARAMETERS)


def test_resolve_fills_every_default_with_its_type():
    p = resolve()
    assert list(p) == list(PARAMETERS)
    for name, par in PARAMETERS.items():
        assert type(p[name]) is par.kind, name
    assert p["neighbours"] == 4 and resolve(dim=3)["neighbours"] == 6
    assert {k: v for k, v in p.items() if k != "neighbours"} == {k: v for k, v in DEFAULTS.items() if k != "neighbours"}


@pytest.mark.parametrize("name, value, message", [
    ("dim", True, "dim: expected an integer"),
    ("stickiness", 0.0, "stickiness: 0.0 is not in [0.0001, 1]"),
    ("stickiness", 1e-300, "stickiness: 1e-300 is not in [0.0001, 1]"),
    ("size", 10 ** 12, "size: 1000000000000 is above 100000"),
    ("launch_factor", 1e200, "launch_factor: 1e+200 is above 100"),
    ("launch_margin", 1e300, "launch_margin: 1e+300 is above 100"),
    ("kill_factor", 1e300, "kill_factor: 1e+300 is above 100"),
    ("max_steps", 10 ** 25, "max_steps: 10000000000000000000000000 is above 2**62"),
    ("max_steps", 2.5, "max_steps: expected an integer, got 2.5"),
    ("max_steps", "5", "max_steps: expected an integer, got '5'"),
    ("size", 4, "size: 4 is below 8"),
    ("seed_shape", "line", "seed_shape: 'line' needs size > 0"),
    ("model", "hex", "model: 'hex' is not one of"),
    ("walkers", 2, "walkers: more than one walker needs size > 0"),
])
def test_each_check_names_its_parameter(name, value, message):
    with pytest.raises(ValueError, match="^" + re.escape(message)):
        resolve(**{name: value})


def test_dir_lists_the_public_api():
    import importlib

    module = importlib.import_module("dlasweep.reporting.folder")  # loaded, it leaves dla.report the function
    assert dla.report is module.report
    assert set(dla.__all__) <= set(dir(dla))
    for name in ("run_sweep", "open_sweep", "cluster_points", "summarise", "report"):
        assert name in dir(dla) and callable(getattr(dla, name)), name


def test_resolve_caches_a_configuration_yet_returns_a_fresh_dict_and_keeps_types_apart():
    first = resolve(model="lattice", jumps=True)
    first["dim"] = 99
    assert resolve(model="lattice", jumps=True)["dim"] == 2
    with pytest.raises(ValueError, match="jumps: expected true or false, got 1"):
        resolve(model="lattice", jumps=1)  # equal to True, and hashed alike
    with pytest.raises(ValueError, match=r"dim: expected an integer, got \[2\]"):
        resolve(dim=[2])  # unhashable: checked without the cache

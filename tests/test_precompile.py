"""Compiling ahead: the names the wheel's build takes (``DLASWEEP_PRECOMPILE``) and ``dlasweep compile``.

That the wheel then carries the kernels, and that its first grow and a sweep's first task compile nothing,
is tests/test_wheel.py's.
"""

import pytest

from dlasweep.cli import main
from dlasweep.sweep import precompile


def test_the_build_refuses_a_model_it_does_not_know_before_compiling_any(monkeypatch):
    done = []
    monkeypatch.setattr(precompile, "precompile", done.append)
    with pytest.raises(ValueError, match="unknown model 'lattice-4d'; one of all, none, lattice-2d"):
        precompile.build("lattice-2d, lattice-4d")
    assert done == []


@pytest.mark.parametrize("kinds, compiled", [
    ("all", ["lattice-2d", "offlattice-2d", "lattice-3d", "offlattice-3d"]),
    (" none ", []),
    ("offlattice-3d,lattice-2d", ["offlattice-3d", "lattice-2d"]),
])
def test_the_build_compiles_the_models_named(monkeypatch, capsys, kinds, compiled):
    done = []
    monkeypatch.setattr(precompile, "precompile", done.append)
    precompile.build(kinds)
    assert done == compiled
    assert [line.split(" kernels")[0] for line in capsys.readouterr().out.splitlines()] == [
        f"dlasweep: compiled the {kind}" for kind in compiled]


def test_a_model_s_first_run_grows_and_measures_a_cluster_of_its_kind(monkeypatch):
    # what ``precompile`` runs is a sweep's first task of the model's default parameters: the grow kernel
    # and the measures a sweep and ``dlasweep grow`` call
    seen = []
    monkeypatch.setattr(precompile, "measure_tasks", lambda tasks, counts, *rest: seen.append((tasks, counts)))
    precompile.precompile("offlattice-3d")
    ((tasks, counts),) = seen
    (task,) = tasks
    assert (task.params["model"], task.params["dim"]) == ("offlattice", 3) and list(counts) == [10]


def test_dlasweep_compile_says_how_long_each_model_took(capsys):
    assert main(["compile", "--model", "lattice-2d"]) == 0
    (line,) = capsys.readouterr().out.splitlines()
    assert line.startswith("lattice-2d: compiled (or loaded) in ")
    assert main(["compile", "--model", "lattice-4d"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "'lattice-4d'" in err

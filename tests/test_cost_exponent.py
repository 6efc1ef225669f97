"""The side-by-side cost exponent workflow: its input checks, its arithmetic and one small run."""

import csv
import importlib.util
import math

import pytest

from conftest import ROOT

spec = importlib.util.spec_from_file_location("cost_exponent", ROOT / "workflows" / "cost_exponent.py")
expo = importlib.util.module_from_spec(spec)
spec.loader.exec_module(expo)


@pytest.mark.parametrize("args, name", [(["--models", "lattice-4d"], "--models"), (["--rounds", "0"], "--rounds"),
                                        (["--n", "1e5", "--short", "1e5"], "--short"),
                                        (["--n", "1e6", "--short", "0.5"], "--short")])
def test_bad_input_names_itself_exits_2_and_writes_nothing(tmp_path, capsys, args, name):
    with pytest.raises(SystemExit) as stop:
        expo.main([*args, "-o", str(tmp_path / "out")])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert name in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def _row(model, ratio, steps_ratio, long_n=10**7, short_n=10**5):
    return {"model": model, "long_n": long_n, "short_n": short_n, "seed": 1, "long_core": 0,
            "long_ns": 300.0 * ratio, "long_steps": 40.0 * steps_ratio, "short_runs": 9, "short_ns": 300.0,
            "short_steps": 40.0}


def test_exponent_is_one_plus_the_cost_ratios_slope_and_the_steps_part_is_the_steps_slope():
    exponent, steps = expo.exponent(_row("lattice-2d", 100 ** 0.07, 100 ** 0.05))
    assert exponent == pytest.approx(1.07) and steps == pytest.approx(0.05)
    exponent, _ = expo.exponent(_row("lattice-2d", 1.0, 1.0))
    assert exponent == pytest.approx(1.0)  # a flat cost a particle


def test_summary_gives_each_round_their_mean_and_the_verdict_only_for_the_targets_n():
    rows = [_row("lattice-2d", 100 ** 0.04, 1.0), _row("lattice-2d", 100 ** 0.10, 1.0),
            _row("lattice-3d", 100 ** 0.20, 100 ** 0.06), _row("offlattice-2d", 100 ** 0.01, 1.0, 10**6, 10**4)]
    lines = expo.summary(rows, "cmd").splitlines()
    assert lines[0] == "`cmd`"
    two, three, small = lines[-3].split(" | "), lines[-2].split(" | "), lines[-1].split(" | ")
    assert two[1:4] == ["1e5 to 1e7", "1.040 (0.000), 1.100 (0.000)", "1.070"]
    assert two[4] == "1.06 (over, rounds on both sides) |"  # the rounds' mean, over its target of 1.06
    assert three[2:5] == ["1.200 (0.060)", "1.200", "1.1 (over) |"]
    assert small[1] == "1e4 to 1e6" and small[4] == "1.06 is for 1e5 to 1e7 |"  # no verdict off the targets' N
    hosts = {"before": {1.0: 10.0, 64.0: 150.0}, "after": {1.0: 11.0, 64.0: 160.0}}
    lines = expo.summary(rows, "cmd", hosts).splitlines()
    assert lines[-2:] == ["- before: host memory, ns a read waiting on the last: 1 MiB 10.0, 64 MiB 150.0",
                          "- after: host memory, ns a read waiting on the last: 1 MiB 11.0, 64 MiB 160.0"]


@pytest.mark.skipif(len(expo.cores()) < 2, reason="the two sides need two cores")
def test_a_small_round_writes_its_row_and_table(tmp_path, monkeypatch):
    monkeypatch.setattr(expo, "read_latency", lambda: {1.0: 10.0})  # its own test: tests/test_host.py
    expo.main(["--models", "lattice-2d", "--n", "2000", "--short", "500", "--rounds", "1", "-o", str(tmp_path)])
    (row,) = csv.DictReader(open(tmp_path / "cost_exponent.csv"))
    assert row["model"] == "lattice-2d" and int(row["long_n"]) == 2000 and int(row["short_runs"]) >= 1
    assert float(row["long_ns"]) > 0 and float(row["short_steps"]) > 1  # a walk takes steps
    exponent = 1 + math.log(float(row["long_ns"]) / float(row["short_ns"])) / math.log(4)
    table = (tmp_path / "cost_exponent.md").read_text()
    assert f"{exponent:.3f}" in table
    assert [line.split(":")[0] for line in table.splitlines() if "host memory" in line] == [
        "- before the rounds", "- after them"]

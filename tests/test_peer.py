"""The fastDLA peer benchmark's input checks and table (running it needs a fastDLA checkout)."""

import importlib.util

import pytest

from conftest import ROOT

spec = importlib.util.spec_from_file_location("peer_fastdla", ROOT / "workflows" / "peer_fastdla.py")
peer = importlib.util.module_from_spec(spec)
spec.loader.exec_module(peer)


@pytest.mark.parametrize("args, name", [([], "--fastdla"), (["--rounds", "0"], "--rounds"),
                                        (["--large-rounds", "0"], "--large-rounds")])
def test_bad_input_names_itself_exits_2_and_writes_nothing(tmp_path, capsys, args, name):
    checkout = tmp_path / "fastDLA"
    checkout.mkdir()
    if name != "--fastdla":
        for source in peer.SOURCES:
            (checkout / source).write_text("")
    with pytest.raises(SystemExit) as stop:
        peer.main(["--fastdla", str(checkout), "-o", str(tmp_path / "out"), *args])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert name in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_summary_gives_medians_and_pairwise_ratios():
    rows = [{"code": code, "n": 1000, "round": k, "seed": k + 1, "seconds": s, "peak_mb": m, "added_mb": a}
            for k, (ours, theirs) in enumerate([(1.0, 3.0), (2.0, 3.0), (4.0, 2.0)])
            for code, s, m, a in (("dlasweep", ours, 200.0, 1.0), ("fastDLA", theirs, 50.0, float("nan")))]
    row = peer.summary(rows, "commit x", "cmd", (0.5, 0.7)).splitlines()[-1].split(" | ")
    assert row[0] == "| 1,000" and row[1] == "3"
    assert row[2] == "2.00 (1.00-4.00)"  # dlasweep's seconds
    assert row[3] == "3.00 (2.00-3.00)"
    assert row[4] == "1.50 (0.50-3.00)"  # 3/1, 3/2, 2/4
    assert row[5] == "200 (1)" and row[6] == "50" and row[7] == "0.25 (0.25-0.25) |"

"""A sweep's progress lines for a log (dlasweep/sweep/progress.py); the terminal's bars are tested through the
command."""

import io

import pytest

from conftest import progress_lines
from dlasweep.sweep import progress


@pytest.mark.parametrize("seconds_each, shown", [
    (0.5, [30, 40, 50, 60, 70, 80, 90, 100]),  # a line each 10% (10 clusters, 5 s)
    (0.02, [70]),                              # 10% in 0.2 s: at most a line a second
    (11.0, list(range(21, 31))),               # a line after each cluster: none for 10 s
])
def test_progress_lines_each_tenth_or_ten_seconds(seconds_each, shown, monkeypatch):
    clock = [0.0]
    monkeypatch.setattr(progress.time, "monotonic", lambda: clock[0])
    log = io.StringIO()
    with progress.Lines(100, initial=20, desc="quick", file=log) as lines:
        for _ in range(10 if seconds_each > 10 else 80):
            clock[0] += seconds_each
            lines.update(1)
    assert progress_lines(log.getvalue()) == shown
    assert all(line.endswith(" left") for line in log.getvalue().splitlines() if "100/100" not in line)

"""The host memory probe: its chain visits every cache line once, and it reports each working set."""

import numpy as np
import pytest

from dlasweep.host import LINE, latency_line, one_cycle, read_latency


@pytest.mark.parametrize("lines", [2, 3, 64, 1000])
def test_the_chain_is_one_cycle_through_every_line(lines):
    chain = one_cycle(lines, np.random.default_rng(lines))
    stride = LINE // 8
    at, seen = 0, []
    for _ in range(lines):
        seen.append(at)
        at = int(chain[at])
    assert at == 0  # back at the start after exactly ``lines`` reads
    assert sorted(seen) == list(range(0, lines * stride, stride))  # each line's first word, once
    assert not chain[np.arange(len(chain)) % stride != 0].any()  # the rest of each line is never read


def test_the_chain_is_random_not_a_stride_the_prefetcher_would_follow():
    chain = one_cycle(4096, np.random.default_rng(0))
    steps = np.diff(chain[:: LINE // 8])
    assert len(set(steps.tolist())) > 1000


def test_read_latency_reports_every_working_set_in_order():
    latency = read_latency(working_sets=(0.0625, 0.5), reads=20_000, rounds=2)
    assert list(latency) == [0.0625, 0.5]
    assert all(0 < ns < 1e4 for ns in latency.values())
    assert latency_line(latency).startswith("host memory, ns a read waiting on the last: 0.0625 MiB ")

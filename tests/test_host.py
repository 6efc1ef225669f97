"""The host memory probe: its chain visits every cache line once, its timed reads read the whole set, and it
reports each working set."""

import numpy as np
import pytest

from dlasweep.bench import host
from dlasweep.bench.host import LINE, latency_line, one_cycle, read_latency


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


def test_every_timed_read_is_of_the_whole_set_even_when_reads_are_fewer_than_its_lines(monkeypatch):
    # 0.5 MiB is 8192 lines; 1000 reads a walk. Each walk must go on where the last ended after a whole lap,
    # or the timed reads would read the first 1000 lines again, a set of 62.5 KiB.
    walks = []
    real = host._walk

    def recorded(chain, at, reads):
        end = real(chain, at, reads)
        walks.append((at, reads, end))
        return end

    monkeypatch.setattr(host, "_walk", recorded)
    read_latency(working_sets=(0.5,), reads=1000, rounds=3)
    (at, lap, end), *timed = walks
    assert at == 0 and lap == 0.5 * 2**20 // LINE  # a whole lap first
    assert [reads for _, reads, _ in timed] == [1000] * 3
    assert [start for start, _, _ in timed] == [end] + [stop for _, _, stop in timed[:-1]]

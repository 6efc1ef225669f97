"""What both growth kernels share: their typed inputs, the outcome and seed
codes, the sticking rule and the checkpoint clock.

The codes are positions in ``dlasweep.params``' tuples, made module-level
integers here so that numba freezes them into the kernels as constants.
"""

from collections import namedtuple

import numpy as np

from .._jit import borrow, clock, inline, jit
from ..params import SEED_SHAPES, STATUSES, drift_vector
from .walk import xo

OK = STATUSES.index("ok")
BOUNDARY = STATUSES.index("boundary")
STEP_LIMIT = STATUSES.index("step_limit")
EXHAUSTED = STATUSES.index("exhausted")

POINT = SEED_SHAPES.index("point")
BLOCK = SEED_SHAPES.index("block")
LINE = SEED_SHAPES.index("line")

GRID_GROWTH = {"lattice": 2.0, "offlattice": 2.0}
"""How much larger each kernel builds its grids when the cluster outgrows them: the lattice's side, the
off-lattice grids' half-width over the cluster. Pages cost memory only once written (``maps.zeroed``), so a
larger grid costs little, while each rebuild costs work: off-lattice it marks every particle again but in the
centre field, which it copies (``offlattice.grid.regrow_grid``); the lattice carries its words, field and the
pyramid's first level over and marks only near the old grid's edge (``lattice.words.regrow``). A factor of 2
means fewer rebuilds for little memory (the factors tried: docs/performance.md). The walks read the grids, so
either value is part of its model's clusters (the fingerprints)."""

STEPS_DTYPE = np.uint32
"""A particle's diffusion time: 4 bytes, not 8, half the memory of 8-byte counts. A
particle takes tens of moves on average; one that would take 2^32 - 1 or more
is recorded as 2^32 - 1 (``diffusion_time``, saturated)."""
MOST_STEPS = np.iinfo(STEPS_DTYPE).max


@jit
def diffusion_time(pending):
    """``pending`` moves as a particle's stored diffusion time (``STEPS_DTYPE``), saturated."""
    return STEPS_DTYPE(min(pending, MOST_STEPS))

Model = namedtuple("Model", [
    "dim", "neighbours", "stickiness", "seed_shape", "size", "launch_box", "launch_factor", "launch_margin",
    "kill_factor", "exact_return", "kill", "jumps", "step", "walkers", "max_steps",
    "noise_reduction", "neighbour_alpha", "contact_distance", "drift", "drift_x", "drift_y", "drift_z",
])
Model.__doc__ = """The resolved model parameters as the kernels take them (a numba named tuple).

Named as in ``dlasweep.params``; ``seed_shape`` is its code (``POINT``,
``BLOCK``, ``LINE``), ``launch_box`` whether ``launch`` is ``box``.
``exact_return`` and ``kill`` are what ``kill_factor`` means for the walk,
derived once (``model_from``): a walker beyond the launch circle returns to it
exactly, or is killed beyond ``kill_factor`` times its radius, or neither
(a box kills at its walls). ``drift_x``, ``drift_y``, ``drift_z`` are the drift as a
vector (``params.drift_vector``), ``drift`` its length.
"""


def model_from(p) -> Model:
    """The kernels' ``Model`` from ``p``, a dict that ``dlasweep.params.resolve`` returned."""
    launch_box = p["launch"] == "box"
    boxed = p["size"] > 0 and p["seed_shape"] != "line"
    return Model(
        dim=int(p["dim"]), neighbours=int(p["neighbours"]), stickiness=float(p["stickiness"]),
        seed_shape=SEED_SHAPES.index(p["seed_shape"]), size=int(p["size"]), launch_box=bool(launch_box),
        launch_factor=float(p["launch_factor"]), launch_margin=float(p["launch_margin"]),
        kill_factor=float(p["kill_factor"]),
        # without a kill circle, walkers beyond the launch circle (line) return to it
        # exactly, unless the box's walls absorb them first or they start on them
        exact_return=bool(p["kill_factor"] == 0.0 and not launch_box and not boxed),
        kill=bool(p["kill_factor"] > 0.0 and not launch_box),
        jumps=bool(p["jumps"]), step=float(p["step"]), walkers=int(p["walkers"]), max_steps=int(p["max_steps"]),
        noise_reduction=int(p["noise_reduction"]), neighbour_alpha=float(p["neighbour_alpha"]),
        contact_distance=float(p["contact_distance"]), drift=float(p["drift"]),
        **dict(zip(("drift_x", "drift_y", "drift_z"), map(float, drift_vector(p)))),
    )


def lockstep_flag(walkers):
    """The growth kernels' ``lockstep`` argument for ``walkers`` walkers: None for one, True for more.

    The kernels branch on ``lockstep is not None``, which numba decides while
    it types them (its dead-branch pruning resolves a comparison with None): a
    growth of one walker is compiled without the lockstep walk, and of more
    without the single walker's, which shortens a cold compile (the compile
    times: docs/performance.md).
    """
    return None if walkers == 1 else True


def drift_flag(drift):
    """The lattice growth kernel's ``drifted`` argument for a ``drift``: None for none, True for one.

    As ``lockstep_flag``: numba prunes the branches on ``drifted is not None`` while it types the
    kernel, so plain DLA's walk is compiled without the drift's moves, and keeps its speed.
    """
    return None if drift == 0.0 else True


def gaussian_flag(step):
    """The off-lattice kernels' ``gaussian`` argument for a model's ``step``: None for 0, True for a Gaussian step.

    As ``lockstep_flag``: the single walker's walk branches on ``gaussian is not
    None``, which numba decides while it types it, so that a growth of exact
    jumps and contacts (``step`` 0) is compiled without the Gaussian step and
    its end-point check (``offlattice.contact.gauss_move``).
    """
    return None if step == 0.0 else True


@borrow
def sticks(stickiness, rng):
    """The sticking rule: a walker at contact sticks with probability
    ``stickiness``, drawn from the numpy Generator ``rng``; at 1 nothing is drawn."""
    return stickiness >= 1.0 or rng.random() < stickiness


@inline
def sticks_xo(stickiness, s0, s1, s2, s3):
    """``sticks`` with the draw from the xoshiro256+ stream held in registers
    (``s0``, ``s1``, ``s2``, ``s3``, ``walk.xo``): whether it sticks with probability
    ``stickiness``, and the stream's new state.

    Inlined into the lattice walk's hot loop; written with one return, as
    numba's inlining of a function with two makes that loop slower
    (docs/performance.md).
    """
    stuck = True
    if stickiness < 1.0:
        s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
        stuck = u < stickiness
    return stuck, s0, s1, s2, s3


@jit
def neighbour_stickiness(stickiness, alpha, occupied, full):
    """The probability to stick at a site with ``occupied`` occupied neighbours (the substrate counted):
    ``stickiness * alpha**(full - occupied)``, ``stickiness`` from ``full`` occupied on (the
    ``neighbour_alpha`` law; Aukrust et al. 1989's ``alpha**(3 - B)`` on the square lattice, ``full``
    3: every neighbour occupied but the one a walker came from)."""
    return stickiness * alpha ** (full - occupied) if occupied < full else stickiness


@jit
def checkpoint(marks, times, passed, count, t0):
    """Record the clock, in seconds since ``t0`` (``_jit.clock``), into ``times`` for every
    mark of ``marks`` that ``count`` particles reach; returns how many marks have passed
    (``passed``: the caller passes it back in)."""
    while passed < len(marks) and marks[passed] <= count:
        times[passed] = clock() - t0
        passed += 1
    return passed


def grown(points, steps, parents, count, status, times, seconds):
    """A kernel's result as ``dlasweep.grow`` takes it: the first ``count``
    points, diffusion times (``steps``) and parents (copied when growth stopped short, so
    that the unused tail is freed), the status code, the times and the seconds
    the growth took in all."""
    if count < len(points):
        points, steps = points[:count].copy(), steps[:count].copy()
    if count < len(parents):
        parents = parents[:count].copy()
    return points, steps, parents, int(status), times, float(seconds)

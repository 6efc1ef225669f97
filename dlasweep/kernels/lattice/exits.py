"""The lattice walk's first-passage jumps: where the walk first leaves a
square (cube), tabulated.

``exit_law`` is the exact law of the exit site from the centre of the square
(cube) of half-width r; ``exit_tables`` pools it by symmetry class into alias
tables for r up to ``TABLE_MAX``, which the growth samples with two draws: a
class (``alias_table``), then a uniform symmetry of the square (``symmetry``).
Beyond ``TABLE_MAX`` the walk is Brownian at the scale of the jump, and
``square_exit`` draws where Brownian motion leaves the square (cube) from the
Brownian law of one face (``face_law``), in ``FACE_BINS`` bins a side.
"""

from functools import cache

import numpy as np

from ..._jit import borrow, jit
from ..stored import kept_on_disk
from ..walk import xo

TABLE_MAX = (0, 0, 64, 24)  # by dimension: largest square (cube) half-width with an exit table
FACE_BINS = (0, 0, 1024, 64)  # by dimension: bins on a side of a face for the Brownian exit
FACE_MODES = 41  # odd Fourier modes up to this in face_law: the next weighs below exp(-64)


@cache
def unit_moves(dim, moore):
    """Unit moves (and contacts) in ``dim`` dimensions: nearest neighbours, or with ``moore``
    the Moore set, as int64 (M, 3) rows; built once a process
    (``functools.cache``): a small cluster grows in milliseconds (docs/performance.md)."""
    grid = np.stack(np.meshgrid(*([np.arange(-1, 2)] * dim), indexing="ij"), -1).reshape(-1, dim)
    norm = np.abs(grid).sum(1)
    keep = norm > 0 if moore else norm == 1
    out = np.zeros((int(keep.sum()), 3), np.int64)
    out[:, :dim] = grid[keep]
    return out


def exit_law(dim, moore, r):
    """Where the lattice walk from the centre first leaves the square (cube) of half-width r.

    The Green's function of the walk killed on the boundary is diagonal in the
    sine basis (the walk's generator is a sum, NN, or a product, Moore, of 1D
    shift operators), so it is exact up to rounding for every r; the exit
    probability of a boundary site is the Green's function summed over the
    interior sites one move away, over the number of moves.

    Returns
    -------
    offsets : int (K, dim), the boundary sites reachable in one move
    probs : float (K,), their exit probabilities (summing to 1)
    """
    n = 2 * r - 1
    m = np.arange(1, n + 1)
    theta = np.pi * m / (n + 1)
    basis = np.sqrt(2.0 / (n + 1)) * np.sin(np.outer(m, theta))  # [site, mode]
    cos = np.meshgrid(*([np.cos(theta)] * dim), indexing="ij")
    if moore:
        eig = (np.prod([1.0 + 2.0 * c for c in cos], axis=0) - 1.0) / (3**dim - 1)
    else:
        eig = sum(cos) / dim
    green = 1.0 / (1.0 - eig)
    for a in range(dim):  # times the centre's coordinates in the basis
        green = green * basis[r - 1].reshape([-1 if b == a else 1 for b in range(dim)])
    for a in range(dim):  # back to sites
        green = np.moveaxis(np.tensordot(basis, green, axes=([1], [a])), 0, a)
    padded = np.zeros((2 * r + 1,) * dim)
    padded[(slice(1, -1),) * dim] = green  # the boundary holds zero
    hits = np.zeros_like(padded)
    for v in unit_moves(dim, moore)[:, :dim]:
        hits += np.roll(padded, tuple(v), axis=tuple(range(dim)))
    sites = np.indices(padded.shape).reshape(dim, -1).T - r
    probs = hits.reshape(-1) / len(unit_moves(dim, moore))
    keep = (np.abs(sites).max(1) == r) & (probs > 0.0)  # NN: corners are never hit first
    return sites[keep], probs[keep]


@jit
def alias_table(probs):
    """Walker's alias table (Vose) for O(1) sampling from ``probs``."""
    k = len(probs)
    scaled = probs * (k / probs.sum())
    cut = np.ones(k)
    alias = np.arange(k).astype(np.int32)
    small = np.zeros(k, np.int64)
    large = np.zeros(k, np.int64)
    ns = nl = 0
    for a in range(k):
        if scaled[a] < 1.0:
            small[ns] = a
            ns += 1
        else:
            large[nl] = a
            nl += 1
    while ns > 0 and nl > 0:
        ns -= 1
        s = small[ns]
        g = large[nl - 1]
        cut[s] = scaled[s]
        alias[s] = g
        scaled[g] -= 1.0 - scaled[s]
        if scaled[g] < 1.0:
            nl -= 1
            small[ns] = g
            ns += 1
    return cut, alias


def symmetry_classes(sites, probs):
    """Pool an exit law by orbits of the square's (cube's) symmetry group.

    The law is invariant under axis permutations and reflections, so it is
    the law of a class (its orbit's total) followed by a uniform symmetry
    applied to the class's representative, the sorted absolute coordinates.

    Returns
    -------
    reps : int (C, dim), representatives, sorted
    probs : float (C,), the classes' probabilities
    """
    keys = np.sort(np.abs(sites), axis=1)
    reps, inverse = np.unique(keys, axis=0, return_inverse=True)
    return reps, np.bincount(inverse.reshape(-1), weights=probs, minlength=len(reps))


def face_law(dim):
    """Where Brownian motion from the centre of the square (cube) [-1, 1]^dim
    first leaves it, in bins of the face x_0 = 1: ``FACE_BINS[dim]`` a side.

    The harmonic measure of the face from the centre is the series
    sum over odd m (and n) of cos(m pi y / 2) [cos(n pi z / 2)] / (2 cosh(pi |(m, n)| / 2)),
    the solution of Laplace's equation in the square (cube) by separation of
    variables; each term's integral over a bin is in closed form. The face
    holds 1 / (2 dim) of the law.

    Returns
    -------
    float (FACE_BINS[dim] ** (dim - 1),), the bins' probabilities, y fastest
    """
    bins = FACE_BINS[dim]
    edges = np.linspace(-1.0, 1.0, bins + 1)
    modes = np.arange(1, FACE_MODES + 1, 2)
    # integral of cos(m pi y / 2) over each bin: [m, bin]
    part = np.diff(np.sin(np.outer(modes, edges) * np.pi / 2), axis=1) * (2.0 / (np.pi * modes[:, None]))
    if dim == 2:
        return (part / (2.0 * np.cosh(np.pi * modes / 2))[:, None]).sum(0)
    weight = 1.0 / (2.0 * np.cosh(np.pi * np.hypot.outer(modes, modes) / 2))  # [m (z), n (y)]
    return (part.T @ weight @ part).reshape(-1)  # [z bin, y bin]


@kept_on_disk
def exit_tables(dim, moore):
    """Alias tables of ``exit_law`` by symmetry class (``symmetry_classes``) for
    half-widths 0..TABLE_MAX[dim] (0 and 1 empty).

    One class per orbit keeps the tables 8 (2D) or 48 (3D) times smaller, so
    they stay in cache though the jumps read them at random.

    Returns
    -------
    start : int64 (R + 2,), entries of half-width r are start[r]:start[r + 1]
    cut, alias : float64, int32 (K,), the alias table (alias indices are local to r)
    offsets : int8 (K, 3), the classes' representatives
    """
    top = TABLE_MAX[dim]
    start = np.zeros(top + 2, np.int64)
    cuts, aliases, offsets = [], [], []
    for r in range(2, top + 1):
        reps, probs = symmetry_classes(*exit_law(dim, moore, r))
        cut, alias = alias_table(probs)
        cuts.append(cut)
        aliases.append(alias)
        off = np.zeros((len(probs), 3), np.int8)
        off[:, :dim] = reps
        offsets.append(off)
        start[r + 1:] = start[r] + len(probs)
    return start, np.concatenate(cuts), np.concatenate(aliases), np.concatenate(offsets)


# module constants, so that the walk's loop reads them without counting references (numba freezes
# them); built by alias_table's Python function, as compiling it would slow every import (docs/performance.md)
FACE_CUT_2D, FACE_ALIAS_2D = alias_table.py_func(face_law(2))
FACE_CUT_3D, FACE_ALIAS_3D = alias_table.py_func(face_law(3))


@borrow
def square_exit(s0, s1, s2, s3, dim):
    """Where Brownian motion from the centre first leaves the square (cube)
    [-1, 1]^dim: a bin of ``face_law`` by its alias table (``FACE_CUT_2D``...),
    a uniform point in it, and a uniform face. The stream's state in registers
    (``walk.xo``).

    Returns
    -------
    s0, s1, s2, s3 : the state
    o0, o1, o2 : the point (o2 = 0 in 2D)
    """
    bins = FACE_BINS[dim]
    s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
    x = u * bins ** (dim - 1)
    b = np.int64(x)
    if dim == 2:
        if x - b >= FACE_CUT_2D[b]:
            b = np.int64(FACE_ALIAS_2D[b])
    elif x - b >= FACE_CUT_3D[b]:
        b = np.int64(FACE_ALIAS_3D[b])
    s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
    y = ((b % bins) + u) * (2.0 / bins) - 1.0
    z = 0.0
    if dim == 3:
        s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
        z = ((b // bins) + u) * (2.0 / bins) - 1.0
    s0, s1, s2, s3, u = xo(s0, s1, s2, s3)
    face = np.int64(u * 2 * dim)
    side = 1.0 if face & 1 else -1.0
    if face >> 1 == 0:
        return s0, s1, s2, s3, side, y, z
    if face >> 1 == 1:
        return s0, s1, s2, s3, y, side, z
    return s0, s1, s2, s3, y, z, side


@jit
def symmetry(g, dim, o0, o1, o2):
    """Symmetry ``g`` (0..7 in 2D, 0..47 in 3D) of the square (cube) applied to (o0, o1, o2).

    Bits 0..dim-1 of ``g`` reflect the axes; the rest pick one of the dim!
    axis permutations (a cyclic shift, then perhaps a swap).
    """
    p = g >> dim
    if dim == 3:
        for _ in range(p >> 1):
            o0, o1, o2 = o1, o2, o0
        p &= 1
    if p:
        o0, o1 = o1, o0
    if g & 1:
        o0 = -o0
    if g & 2:
        o1 = -o1
    if dim == 3 and g & 4:
        o2 = -o2
    return o0, o1, o2

"""The cluster as a tree: chemical distances, Horton-Strahler orders, branches.

Pure functions of a parent array (``Cluster.parents``: each particle's
parent precedes it, -1 for a root), compiled loops in index order, so that
no recursion is needed and a path of 10^7 particles is as easy as a bushy
tree (docs/performance.md, "Measures").

Horton-Strahler order: a leaf has order 1; a particle whose children's
highest order k is reached by two or more of them has order k + 1, else k.
A *branch* of order k is a maximal chain of particles of order k: the
particles of order k whose parent has a higher order, or is none, each
start one (seen from the root). The bifurcation ratio ``R_b`` is
``N_k / N_{k+1}``, from the least-squares slope of ``ln N_k`` against k
over the orders with at least ``MIN_BRANCHES`` branches. 2D DLA: 5.2 in
simulations, 4.9 from the branched-growth model (Halsey 1997).
"""

from __future__ import annotations

import numpy as np

from .._jit import jit

MIN_BRANCHES = 10
"""Fewest branches an order needs to enter the bifurcation ratio. A finite cluster's highest orders are
cut short (their branches still growing, or too few to count): over 64 2D off-lattice clusters of 10^5
the successive ratios of the mean counts are 5.34, 5.18, 5.18, 4.66, 3.72, 2.96 from order 1 up, and
the mean R_b with thresholds 1, 3, 10 and 30 is 4.20, 4.56, 5.03 and 5.11."""
CHEMICAL_WINDOW = (0.05, 0.5)
"""Window of chemical distances, as fractions of the largest, over which mass ~ l**d_l is fitted:
below it the lattice (or disk) scale, above it the growing outer branches."""


@jit
def generations(parents) -> np.ndarray:
    """Chemical distance of each particle to its root: the bonds along the tree (a root: 0).

    Parameters
    ----------
    parents : int (n,)
        Each particle's parent, earlier in the array, or -1.

    Returns
    -------
    int64 (n,)
    """
    n = len(parents)
    out = np.zeros(n, np.int64)
    for i in range(n):
        p = parents[i]
        if p >= 0:
            out[i] = out[p] + 1
    return out


@jit
def strahler(parents) -> np.ndarray:
    """Horton-Strahler order of each particle (module docstring).

    Children come after their parent, so one pass from the last particle
    to the first sees every child before its parent.

    Returns
    -------
    int32 (n,)
    """
    n = len(parents)
    top = np.zeros(n, np.int32)  # highest order among a particle's children so far
    ties = np.zeros(n, np.int32)  # how many children reach it
    order = np.zeros(n, np.int32)
    for i in range(n - 1, -1, -1):
        if top[i] == 0:
            order[i] = 1
        else:
            order[i] = top[i] + 1 if ties[i] >= 2 else top[i]
        p = parents[i]
        if p >= 0:
            if order[i] > top[p]:
                top[p] = order[i]
                ties[p] = 1
            elif order[i] == top[p]:
                ties[p] += 1
    return order


def branch_counts(parents, orders=None) -> np.ndarray:
    """Number of branches of each Horton-Strahler order: ``counts[k - 1]`` is N_k.

    Parameters
    ----------
    parents : int (n,)
    orders : int (n,), optional
        ``strahler(parents)``, when already computed.

    Returns
    -------
    int64 (Omega,), Omega the highest order
    """
    parents = np.asarray(parents)
    orders = strahler(parents) if orders is None else orders
    if len(parents) == 0:
        return np.zeros(0, np.int64)
    above = np.where(parents >= 0, orders[np.maximum(parents, 0)], np.iinfo(np.int32).max)
    starts = orders[above > orders]
    return np.bincount(starts, minlength=int(orders.max()) + 1)[1:].astype(np.int64)


def bifurcation_ratio(counts, min_branches=MIN_BRANCHES) -> float:
    """``R_b`` from branch counts per order: the fit over the orders with at least ``min_branches``
    (module docstring); NaN when fewer than two orders have that many."""
    counts = np.asarray(counts, np.float64)
    k = np.flatnonzero(counts >= max(min_branches, 1e-300)) + 1
    if len(k) < 2:
        return np.nan
    return float(np.exp(-np.polyfit(k, np.log(counts[k - 1]), 1)[0]))


def chemical_dimension(parents, window=CHEMICAL_WINDOW) -> float:
    """The chemical-distance dimension d_l: mass within chemical distance l grows as l**d_l.

    A least-squares slope of ln M(l) against ln l for l in ``window`` (fractions
    of the largest distance); NaN when that holds fewer than 3 distances.
    """
    gen = generations(np.asarray(parents))
    top = int(gen.max()) if len(gen) else 0
    mass = np.cumsum(np.bincount(gen, minlength=top + 1))  # M(l): particles within l bonds of a root
    ls = np.arange(top + 1)
    keep = (ls >= max(window[0] * top, 1)) & (ls <= window[1] * top)
    if keep.sum() < 3:
        return np.nan
    return float(np.polyfit(np.log(ls[keep]), np.log(mass[keep]), 1)[0])


def branching(parents) -> dict:
    """Everything this module measures of one tree: orders, branch counts, R_b, d_l and the deepest generation."""
    parents = np.asarray(parents)
    orders = strahler(parents)
    counts = branch_counts(parents, orders)
    return {"orders": orders, "branch_counts": counts, "bifurcation_ratio": bifurcation_ratio(counts),
            "chemical_dimension": chemical_dimension(parents),
            "max_generation": int(generations(parents).max()) if len(parents) else 0}


@jit
def branch_paths(parents, orders):
    """Every branch as a path of particles, for drawing: each from its junction (its first particle's
    parent, when there is one) along the branch to its tip.

    Parameters
    ----------
    parents : int (n,)
    orders : int (n,)
        ``strahler(parents)``.

    Returns
    -------
    nodes : int64 (m,)
        The paths, one after the other.
    offsets : int64 (b + 1,)
        Branch j is ``nodes[offsets[j]:offsets[j + 1]]``.
    branch_orders : int32 (b,)
        Each branch's order; branches come by order, then by their first particle.
    """
    n = len(parents)
    # the one child of the same order that carries a branch on (two would raise the order)
    onward = np.full(n, -1, np.int64)
    heads = 0
    for i in range(n):
        p = parents[i]
        if p >= 0 and orders[p] == orders[i]:
            onward[p] = i
        else:
            heads += 1
    top = 0
    for i in range(n):
        top = max(top, orders[i])
    nodes = np.empty(n + heads, np.int64)
    offsets = np.zeros(heads + 1, np.int64)
    branch_orders = np.empty(heads, np.int32)
    b = 0
    m = 0
    for k in range(1, top + 1):
        for i in range(n):
            p = parents[i]
            if orders[i] != k or (p >= 0 and orders[p] == k):
                continue
            if p >= 0:
                nodes[m] = p
                m += 1
            j = i
            while j >= 0:
                nodes[m] = j
                m += 1
                j = onward[j]
            branch_orders[b] = k
            b += 1
            offsets[b] = m
    return nodes[:m], offsets, branch_orders

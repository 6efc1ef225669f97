"""Square and simple-cubic lattice DLA.

- ``exits``: the exact law of where the lattice walk first leaves a square
  (cube), tabulated as alias tables by symmetry class;
- ``words``: the bit-packed occupancy of the sites, and exact Chebyshev
  distances a few sites out from whole 64-bit words;
- ``walker``: the pieces of one walker's walk (single steps, contact, the
  distance bounds, release) and the attachment of a particle;
- ``lockstep``: many walkers at once;
- ``lattice_growth``: the walk from release to contact, and ``grow_lattice``,
  the entry point;
- ``parents``: who stuck to whom, found from the sites after growth.
"""

from .exits import exit_tables
from .lattice_growth import grow_lattice

__all__ = ["exit_tables", "grow_lattice"]

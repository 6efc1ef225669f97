"""Off-lattice DLA: unit-diameter disks (2D) and spheres (3D).

Two particles touch when their centres are exactly one diameter apart.

- ``geometry``: where the grid lies (``gi``, ``gf``);
- ``celllist``: the cell list, which finds the particles near a point;
- ``grid``: the hierarchical maps, the centre field and pyramid, which bound
  the free distance of a walker from below, built and regrown with the cell list;
- ``contact``: the exact ray cast to contact, the Gaussian steps and the
  rebound of a walker that did not stick;
- ``walker``: one walker's release, its walk from release to contact, and
  the attachment of the particle it becomes;
- ``lockstep``: many walkers at once;
- ``offlattice_growth``: the growth of a cluster from those, and
  ``grow_offlattice``, the entry point.

Far from the cluster a walker moves by walk-on-spheres jumps: it jumps
uniformly onto the sphere whose radius is a lower bound on its free
distance: near the cluster the centre field (the distance from the centre
of a coarse cell to the nearest particle's unit cell, less the walker's way
to that centre, the largest over the cells whose centres surround the
walker), further out the centre pyramid (the same from the centre of the
walker's own cell, for ever coarser cells to the nearest held cell of the
level below), at contact
range and beside periodic sides the largest clear level of the dilated
maps, and the bounding circle of the cluster. Outside the launch
circle it returns exactly (``walk.return_to_sphere``; above a substrate's
launch line, ``walk.return_to_plane``).

Near the cluster, exact nearest distances come from the cell list, cached
as a neighbour list around an anchor point. When the free distance (surface
gap) drops below ``EPS`` the walker moves by ``RAY`` along a uniform
direction with an exact ray cast, so it stops exactly at contact (centre
distance 1 to rounding, never less) and never passes through a branch. The
contact point is biased by O(EPS).

``step > 0`` replaces the end game by fixed Gaussian steps with an end-point
overlap check (``contact.gauss_move``), the naive scheme, kept to show where
it fails.

Rules where the model table leaves a choice:

* Stickiness: at each contact the walker sticks with probability s; if not,
  it moves away by a ray-cast move of length ``REJECT`` = 1 along a uniform
  direction of the outward half-space (step > 0: it stays at the contact and
  takes its next Gaussian step from there).
* Box (size > 0): absorbing walls at +-size/2 (a walker within ``EPS`` of a
  wall is removed). Circle launch stops with ``boundary`` when the launch
  circle comes within one diameter of the walls; box launch releases walkers
  uniformly on the surface one diameter inside the walls and stops with
  ``boundary`` when a particle centre comes within 2 of the walls.
  ``kill_factor`` is ignored with box launch (the walls kill).
* Substrate (seed_shape line): centres touch it at up-coordinate 0; periodic
  sides of width ``size`` (stored coordinates in [0, size)). Circle launch:
  launch line/plane at launch_factor*h_max + launch_margin, no ceiling. Box
  launch: walkers released at height size-1, absorbing ceiling at size,
  ``boundary`` when h_max >= size - 2.
* walkers > 1: walkers start uniformly in the box (not overlapping the seed),
  take single steps in turn (length 1 with a ray cast, or Gaussian), and are
  removed at the walls; a walker found overlapping a newly attached particle
  merges into it (is removed).
* step > 0 with jumps: walk-on-spheres while the free distance exceeds
  ``GAUSS_JUMP * step``, fixed Gaussian steps nearer than that.

Random numbers: the numpy Generator passed in seeds a xoshiro256+ stream
kept in registers for the walk's directions; the Generator itself draws the
exact returns, stickiness and Gaussian steps. Both are deterministic given
the Generator, so a cluster is a function of its seed.

Memory: besides the points (16 or 24 bytes each), the diffusion times (4),
the parents (4), the cell-list links (4) and in 3D the attachment number of
each stored row (4: the rows are kept cell after cell, ``celllist.sort_cells``
and ``celllist.sort_tail``, so that a gather reads a cell's particles from a stretch or two;
``sort_tail`` holds 12 bytes a row attached since the last full sort, a fifth at most), the grids take
about a bit per unit cell (maps), a byte per cell of side ``2**FS`` (centre field) and 4 bytes per tile of
64 cell-list cells (directory) over a square ``GROW`` times the cluster's
extent, and 256 bytes per tile that holds particles. When the cluster
outgrows them they are dropped, and the larger ones built in the walk
loop's next pass: numba frees an array held across a loop's passes only
when the pass ends, so building them in the same pass would hold both. The
centre field alone (with the pyramid above it) is kept until the new grid
has copied it and the pyramid's first level (``grid.regrow_grid``: no
particle lowers their cells again but those near the old grid's edge), its
pages then handed back to the OS.
(With walkers > 1 both are still held during a rebuild: the box bounds them.)

Speed note: numba counts the references of the arrays a function hands on,
with atomic increments and decrements, a large share of a growth's time
(each inlined gather hands on 11 arrays; docs/performance.md). The walk, the attachment
and their helpers are therefore compiled by ``_jit.borrow``, without
reference counting (they allocate nothing). The walk inlines the direction
draw, the gather of the neighbour list and the ray cast (``walk.xdir``,
``celllist.gather``, ``contact.ray_to``) and spells out the map query (a
pinned copy of ``grid.walk_bound``).
"""

from .contact import EPS
from .offlattice_growth import grow_offlattice

__all__ = ["EPS", "grow_offlattice"]

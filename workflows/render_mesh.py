"""Render a cluster's mesh file (.ply or .obj, as `dlasweep grow -o` or `dlasweep export` write it) to a PNG:
loaded by trimesh, as Blender or ParaView would load it, and drawn by matplotlib, lit by the face normals.

    .venv/bin/dlasweep grow -n 3000 --dim 3 --model offlattice --seed 2 -o cluster.ply --mesh tubes
    .venv/bin/python workflows/render_mesh.py cluster.ply -o results/tree/mesh.png

Needs trimesh (the test extra).
"""

import argparse
from pathlib import Path

import numpy as np
import trimesh
from matplotlib import colormaps
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

LIGHT = np.array([0.4, 0.3, 0.87])


def render(mesh_path: Path, out: Path, inches=6.0, dpi=150):
    mesh = trimesh.load(mesh_path, process=False)
    triangles = mesh.vertices[mesh.faces]
    shade = 0.25 + 0.75 * np.clip(mesh.face_normals @ (LIGHT / np.linalg.norm(LIGHT)), 0, 1)
    height = triangles[:, :, 2].mean(axis=1)
    span = np.ptp(height) or 1.0
    colours = colormaps["viridis"]((height - height.min()) / span)
    colours[:, :3] *= shade[:, None]
    fig = Figure(figsize=(inches, inches), dpi=dpi)
    ax = fig.add_subplot(projection="3d")
    ax.add_collection3d(Poly3DCollection(triangles, facecolors=colours, linewidths=0))
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    half = (hi - lo).max() / 2
    for axis, centre in zip("xyz", (lo + hi) / 2):
        getattr(ax, f"set_{axis}lim")(centre - half, centre + half)
    ax.set_box_aspect((1, 1, 1), zoom=1.4)  # the axes are off: their margin is empty
    ax.set_axis_off()
    ax.view_init(elev=25, azim=35)
    fig.suptitle(f"{mesh_path.name}: {len(mesh.vertices)} vertices, {len(mesh.faces)} faces, read by trimesh "
                 f"(colour: height)", fontsize=8)
    fig.savefig(out)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mesh", type=Path, help=".ply or .obj file")
    parser.add_argument("-o", "--output", type=Path, required=True, help="PNG to write")
    args = parser.parse_args(argv)
    print(render(args.mesh, args.output))


if __name__ == "__main__":
    main()

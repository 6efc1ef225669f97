"""Exports of a cluster (``dlasweep.data.export``), read back by real readers: csv, plyfile and trimesh, xml."""

import csv
import xml.etree.ElementTree as ET

import numpy as np
import plyfile
import pytest
import trimesh

import dlasweep as dla
from dlasweep.data import export
from dlasweep.data import netcdf as store
from dlasweep.measures import tree

CASES = {
    "off-2d": dict(model="offlattice"),
    "off-3d": dict(model="offlattice", dim=3),
    "lattice-2d": dict(),
    "off-line": dict(model="offlattice", seed_shape="line", size=24),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def cluster(request):
    return dla.grow(300, seed=4, **CASES[request.param])


def _xyz(c):
    return np.pad(c.points.astype(np.float64), ((0, 0), (0, 3 - c.points.shape[1])))


def test_csv_holds_every_particle_as_dlaf_writes_it(cluster, tmp_path):
    path = export.export_cluster(cluster, tmp_path / "c.csv")
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    axes = list("xyz"[:cluster.points.shape[1]])
    assert rows[0] == ["id", "parent", *axes, "diffusion_time"]
    table = np.array(rows[1:], dtype=np.float64)
    np.testing.assert_array_equal(table[:, 0], np.arange(cluster.n))
    np.testing.assert_array_equal(table[:, 1], cluster.parents)
    np.testing.assert_array_equal(table[:, 2:-1], cluster.points)  # %.17g: every float back exactly
    np.testing.assert_array_equal(table[:, -1], cluster.steps)


def test_ply_spheres_load_in_plyfile_and_trimesh(cluster, tmp_path):
    path = export.export_cluster(cluster, tmp_path / "c.ply")
    ply = plyfile.PlyData.read(str(path))
    assert ply["vertex"].count == 12 * cluster.n and ply["face"].count == 20 * cluster.n
    vertices = np.stack([ply["vertex"][a] for a in "xyz"], 1).reshape(cluster.n, 12, 3)
    radius = np.linalg.norm(vertices - _xyz(cluster)[:, None], axis=2)
    np.testing.assert_allclose(radius, export.RADIUS, atol=1e-3)  # float32 vertices
    mesh = trimesh.load(path, process=False)
    assert len(mesh.vertices) == 12 * cluster.n and len(mesh.faces) == 20 * cluster.n
    assert mesh.faces.max() == len(mesh.vertices) - 1
    # outward faces: each closed icosahedron has a positive volume
    assert mesh.volume == pytest.approx(cluster.n * 2.5362 * export.RADIUS ** 3, rel=1e-3)


def test_obj_is_the_same_mesh(cluster, tmp_path):
    ply = trimesh.load(export.export_cluster(cluster, tmp_path / "c.ply"), process=False)
    obj = trimesh.load(export.export_cluster(cluster, tmp_path / "c.obj"), process=False)
    np.testing.assert_allclose(obj.vertices, ply.vertices, atol=2e-6 * max(1, np.abs(ply.vertices).max()))
    np.testing.assert_array_equal(obj.faces, ply.faces)


def test_tubes_run_along_every_bond(cluster, tmp_path):
    mesh = trimesh.load(export.export_cluster(cluster, tmp_path / "t.ply", mesh="tubes"), process=False)
    child = np.flatnonzero(cluster.parents >= 0)
    sides = export.TUBE_SIDES
    assert len(mesh.vertices) == len(mesh.faces) == 2 * sides * len(child)
    rings = mesh.vertices.reshape(len(child), 2, sides, 3)
    start = rings[:, 0].mean(axis=1)
    np.testing.assert_allclose(start, _xyz(cluster)[child], atol=1e-3)
    length = np.linalg.norm(rings[:, 1].mean(axis=1) - start, axis=1)
    if cluster.params["model"] == "offlattice":
        np.testing.assert_allclose(length, 1.0, atol=1e-3)  # a bond is a contact: one diameter
    else:
        assert ((length > 0.99) & (length < 1.01)).all()  # nearest neighbours on the lattice
    np.testing.assert_allclose(np.linalg.norm(rings[:, 0] - start[:, None], axis=2), export.TUBE_RADIUS, atol=1e-3)


def _polylines(path):
    root = ET.parse(path).getroot()
    ns = {"svg": "http://www.w3.org/2000/svg"}
    out = []
    for group in root.iterfind(".//svg:g[@class]", ns):
        order = int(group.get("class").removeprefix("order-"))
        assert float(group.get("stroke-width")) == pytest.approx(export.STROKE * order)
        for line in group.iterfind("svg:polyline", ns):
            out.append((order, np.array([p.split(",") for p in line.get("points").split()], float)))
    return out


def test_svg_tree_is_one_polyline_per_branch_and_covers_every_bond(cluster, tmp_path):
    lines = _polylines(export.export_cluster(cluster, tmp_path / "c.svg"))
    orders = tree.strahler(cluster.parents)
    points = cluster.points[:, :2].astype(np.float64)
    if cluster.params["seed_shape"] != "line":  # periodic sides cut some branches in pieces
        counts = np.bincount([k for k, _ in lines], minlength=orders.max() + 1)[1:]
        np.testing.assert_array_equal(counts, tree.branch_counts(cluster.parents))
    drawn = {tuple(np.r_[a, b]) for _, xy in lines for a, b in zip(xy[:-1], xy[1:])}
    child = np.flatnonzero(cluster.parents >= 0)
    bonds = {tuple(float(f"{v:.3f}") for v in np.r_[points[p], points[c]])
             for c, p in zip(child, cluster.parents[child])}
    wrapped = {b for b in bonds if abs(b[0] - b[2]) > 1.5}  # across a periodic side: not drawn as one segment
    assert drawn == bonds - wrapped


def test_streamed_in_small_chunks_the_files_are_the_same(cluster, tmp_path, monkeypatch):
    whole = {s: export.export_cluster(cluster, tmp_path / f"whole{s}").read_bytes() for s in (".csv", ".ply", ".obj")}
    monkeypatch.setattr(export, "CHUNK", 7)
    for s, data in whole.items():
        assert export.export_cluster(cluster, tmp_path / f"chunked{s}").read_bytes() == data


def test_a_stored_cluster_exports_from_python(tmp_path):
    c = dla.grow(200, seed=2, model="offlattice")
    store.save(store.cluster_dataset(c, 2), tmp_path / "one.nc")
    with dla.open_sweep(tmp_path / "one.nc") as ds:
        dla.export_cluster(ds, tmp_path / "one.csv", cluster=0)
        with pytest.raises(IndexError):
            dla.export_cluster(ds, tmp_path / "two.csv", cluster=1)
    assert (tmp_path / "one.csv").read_bytes() == export.export_cluster(c, tmp_path / "direct.csv").read_bytes()
    assert not (tmp_path / "two.csv").exists()


def test_bad_exports_write_nothing(tmp_path):
    c = dla.grow(50, seed=1)
    with pytest.raises(ValueError, match="c.stl: expected a file ending in .csv, .ply, .obj, .svg"):
        export.export_cluster(c, tmp_path / "c.stl")
    with pytest.raises(ValueError, match="mesh: 'cubes' is not one of spheres, tubes"):
        export.export_cluster(c, tmp_path / "c.ply", mesh="cubes")
    c.parents = None
    with pytest.raises(ValueError, match="no parents"):
        export.export_cluster(c, tmp_path / "c.csv")
    assert list(tmp_path.iterdir()) == []


def test_the_commands_write_every_format(run_cli, tmp_path):
    c = dla.grow(120, seed=3, stickiness=0.5)
    for name, extra in (("g.csv", []), ("g.ply", ["--mesh", "tubes"]), ("g.obj", []), ("g.svg", ["--style", "tree"]),
                        ("g.png", ["--style", "tree"])):
        status, out, err = run_cli("grow", "-n", "120", "--seed", "3", "--stickiness", "0.5", "-o",
                                   tmp_path / name, *extra)
        assert status == 0 and out == f"{tmp_path / name}: 120 particles\n", err
    assert (tmp_path / "g.csv").read_bytes() == export.export_cluster(c, tmp_path / "direct.csv").read_bytes()
    assert len(_polylines(tmp_path / "g.svg")) == tree.branch_counts(c.parents).sum()
    assert (tmp_path / "g.png").read_bytes()[:4] == b"\x89PNG"
    # the default .svg is still the picture of disks
    status, _, err = run_cli("grow", "-n", "120", "--seed", "3", "-o", tmp_path / "disks.svg")
    assert status == 0 and "polyline" not in (tmp_path / "disks.svg").read_text()
    # from a stored cluster
    store.save(store.cluster_dataset(c, 3), tmp_path / "one.nc")
    status, out, err = run_cli("export", tmp_path / "one.nc", "--cluster", "0", "-o", tmp_path / "e.csv")
    assert status == 0 and out == f"{tmp_path / 'e.csv'}: cluster 0, 120 particles\n", err
    assert (tmp_path / "e.csv").read_bytes() == (tmp_path / "g.csv").read_bytes()
    status, out, err = run_cli("grow", "-n", "1", "-o", tmp_path / "seed.csv")
    assert status == 0 and out == f"{tmp_path / 'seed.csv'}: 1 particle\n", err


@pytest.mark.parametrize("argv, named", [
    (["grow", "-n", "50", "-o", "c.stl"], "dlasweep grow: -o c.stl: expected a file ending in .nc, .png, .svg, "
                                          ".csv, .ply, .obj"),
    (["grow", "-n", "50", "-o", "c.csv", "--mesh", "tubes"], "dlasweep grow: --mesh: applies to .ply, .obj files, "
                                                             "not to c.csv"),
    (["grow", "-n", "50", "-o", "c.ply", "--style", "tree"], "dlasweep grow: --style: applies to .png, .svg files, "
                                                             "not to c.ply"),
    (["grow", "-n", "50", "-o", "c.svg", "--style", "lines"], "dlasweep grow: argument --style: invalid choice"),
    (["export", "one.nc", "--cluster", "1", "-o", "c.ply"], "dlasweep export: --cluster: 1 is not in [0, 0]"),
    (["export", "one.nc", "--cluster", "-1", "-o", "c.ply"], "dlasweep export: --cluster: -1 is not in [0, 0]"),
    (["export", "one.nc", "--cluster", "0", "-o", "c.txt"], "dlasweep export: -o c.txt: expected a file ending in"),
    (["export", "none.nc", "--cluster", "0", "-o", "c.csv"], "dlasweep export: none.nc: no such file"),
])
def test_bad_input_exits_2_with_one_line_and_writes_nothing(argv, named, tmp_path, monkeypatch):
    import subprocess
    import sys

    store.save(store.cluster_dataset(dla.grow(20, seed=1), 1), tmp_path / "one.nc")
    before = set(tmp_path.iterdir())
    done = subprocess.run([sys.executable, "-m", "dlasweep", *argv], cwd=tmp_path, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 2 and done.stderr.startswith(named) and done.stderr.count("\n") == 1, done.stderr
    assert set(tmp_path.iterdir()) == before


def test_a_large_cluster_streams_without_a_copy_of_the_file_in_memory(tmp_path):
    import tracemalloc

    from dlasweep.growth.cluster import Cluster
    from dlasweep.params import resolve

    n = 1_000_000
    rng = np.random.default_rng(0)
    c = Cluster(rng.normal(size=(n, 2)) * 300, rng.integers(0, 100, n), "ok", resolve(model="offlattice"),
                parents=np.arange(n, dtype=np.int32) - 1)
    for name in ("big.csv", "big.ply"):
        tracemalloc.start()
        path = export.export_cluster(c, tmp_path / name)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        # a chunk at a time: the peak is a small part of the file (58 MB of text, 404 MB of mesh)
        assert peak < path.stat().st_size / 3, (name, peak, path.stat().st_size)
        path.unlink()

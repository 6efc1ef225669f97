"""Pictures of one cluster: pixel sizes as asked, lattice sites without gaps, three views in 3D, the box
and substrate drawn, the parameters in the title, bad picture options refused."""

import numpy as np
import pytest
from matplotlib import colormaps
from matplotlib.image import imread

import dlasweep as dla
from conftest import files_under
from dlasweep.reporting.pictures import cluster_figure, describe, draw_cluster, draw_points


def png_size(path):
    """Width and height from the PNG header (IHDR)."""
    head = path.read_bytes()[:24]
    assert head.startswith(b"\x89PNG\r\n\x1a\n")
    return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")


def block(side, dim=2):
    """Every site of a cube of ``side`` sites, in a scrambled attachment order."""
    sites = np.stack(np.meshgrid(*[np.arange(side)] * dim, indexing="ij"), axis=-1).reshape(-1, dim)
    return np.random.default_rng(0).permutation(sites)


@pytest.mark.parametrize("dim", [2, 3])
def test_png_has_the_requested_pixel_size(dim, tmp_path):
    c = dla.grow(200, seed=1, dim=dim)
    path = draw_cluster(c.points, c.params, tmp_path / "c.png", inches=5, dpi=200)
    assert png_size(path) == (1000, 1000)
    assert png_size(draw_cluster(c.points, c.params, tmp_path / "d.png", inches=7.3, dpi=137)) == (1000, 1000)


def test_default_resolution_fits_the_cluster(tmp_path):
    small, large = dla.grow(100, seed=1), dla.grow(100_000, seed=1)
    width, _ = png_size(draw_cluster(small.points, small.params, tmp_path / "s.png"))
    assert 1000 < width <= 4000
    extent = np.ptp(large.points, axis=0).max() + 1
    assert extent > 1000  # a pixel a site needs more than the smallest picture: not 660 pixels
    assert extent < png_size(draw_cluster(large.points, large.params, tmp_path / "l.png"))[0] <= 4000


@pytest.mark.parametrize("side, inches, dpi", [(40, 6, None), (40, 6, 100), (37, 3, 77), (400, 2, 100)])
def test_lattice_sites_are_drawn_without_gaps(side, inches, dpi, tmp_path):
    path = draw_cluster(block(side), {}, tmp_path / "block.png", inches=inches, dpi=dpi)
    image = imread(path)[..., :3]
    # The block is where the picture has colour (the title is black, the background white).
    rows, cols = np.nonzero(np.ptp(image, axis=-1) > 0.05)
    inside = image[rows.min() + 1:rows.max(), cols.min() + 1:cols.max()].reshape(-1, 3)
    # Every pixel inside shows a site's own colour, none blended with the white behind (a seam).
    shades = np.unique(inside, axis=0)
    lut = colormaps["viridis"](np.linspace(0.0, 1.0, 256))[:, :3]
    assert len(shades) and (np.abs(shades[:, None] - lut).max(axis=-1).min(axis=1) <= 2.5 / 255).all()
    if dpi is None:  # the default: every site the same whole number of pixels
        assert (cols.max() + 1 - cols.min()) % side == 0 and rows.max() - rows.min() == cols.max() - cols.min()


def test_3d_draws_three_views_and_nearer_particles_cover_farther_ones():
    # Two particles above one another: the first attached (purple) is nearer the top view's viewer.
    points = np.array([[0, 0, 5], [0, 0, 0], [3, 0, 0]])
    fig = cluster_figure(points, {"dim": 3})
    top, side_xz, side_yz = fig.axes
    assert len(fig.axes) == 3
    assert top.get_xlim() == side_xz.get_xlim() and side_xz.get_ylim() == side_yz.get_ylim()
    image = top.images[0]
    x0, x1, y0, _ = image.get_extent()
    pixels = image.get_array()
    block = (x1 - x0) / pixels.shape[1]  # sites per pixel
    shown = pixels[int(-y0 // block), int(-x0 // block)]  # the pixel of site (0, 0)
    np.testing.assert_allclose(shown, np.array(colormaps["viridis"](0.0)) * 255, atol=1)  # the nearest: no fog


def gids(ax):
    return {artist.get_gid() for artist in ax.get_children()} - {None}


@pytest.mark.parametrize("model", ["lattice", "offlattice"])
def test_box_and_substrate_are_drawn(model):
    box = cluster_figure(dla.grow(50, seed=1, model=model, size=40).points, {"model": model, "size": 40})
    assert gids(box.axes[0]) == {"box"}
    (wall,) = [a for a in box.axes[0].patches if a.get_gid() == "box"]
    assert wall.get_width() == 40 and wall.get_x() == (-20.5 if model == "lattice" else -20.0)

    line = {"model": model, "seed_shape": "line", "size": 32}
    flat = cluster_figure(dla.grow(50, seed=1, **line).points, line)
    assert gids(flat.axes[0]) == {"substrate", "periodic"}
    roofed = {**line, "dim": 3, "launch": "box"}
    top, side_xz, side_yz = cluster_figure(dla.grow(50, seed=1, **roofed).points, roofed).axes
    assert gids(top) == {"substrate"} and gids(side_xz) == gids(side_yz) == {"substrate", "periodic", "ceiling"}


def test_title_names_the_parameters_that_differ_from_their_defaults():
    c = dla.grow(30, seed=7, stickiness=0.3, jumps=False)
    (title,) = [t.get_text() for t in cluster_figure(c.points, c.params, seed=7).texts]
    assert "lattice DLA in 2D, N = 30, seed 7" in title and "stickiness=0.3, jumps=false" in title
    assert "launch" not in title and "neighbours" not in title
    assert describe({"dim": 3}, 10) == ("lattice DLA in 3D, N = 10", [])  # 6 neighbours is 3D's default
    assert describe({"neighbours": 8}, 10, status="boundary")[1] == ["neighbours=8"]
    assert "stopped: boundary" in describe({}, 10, status="boundary")[0]


def test_the_report_gallery_call_still_draws():
    from matplotlib.figure import Figure

    for dim in (2, 3):
        ax = Figure().subplots()
        draw_points(ax, block(10, dim).astype(float), True, 3.0)
        assert len(ax.images) == 1
        ax = Figure().subplots()
        draw_points(ax, block(10, dim).astype(float), False, 3.0)
        assert len(ax.collections) == 1


@pytest.mark.parametrize("argv, named", [
    (["--dpi", "5"], "--dpi"),
    (["--dpi", "many"], "--dpi"),
    (["--dpi", "nan"], "--dpi"),
    (["--size-inches", "0"], "--size-inches"),
    (["--size-inches", "100"], "--size-inches"),
    (["--size-inches", "10", "--dpi", "2000"], "--dpi"),
])
def test_bad_picture_options_exit_2_naming_them(argv, named, run_cli, tmp_path):
    status, out, err = run_cli("grow", "-n", "20", *argv, "-o", tmp_path / "c.png")
    assert status == 2 and out == "" and len(err.strip().splitlines()) == 1 and named in err, err
    status, _, err = run_cli("grow", "-n", "20", "--dpi", "100", "-o", tmp_path / "c.nc")
    assert status == 2 and "--dpi" in err and ".png" in err
    assert files_under(tmp_path) == set()


def test_grow_draws_the_size_asked_and_svg_still_works(run_cli, tmp_path):
    status, _, err = run_cli("grow", "-n", "200", "--size-inches", "4", "--dpi", "150", "-o", tmp_path / "c.png")
    assert status == 0, err
    assert png_size(tmp_path / "c.png") == (600, 600)
    status, _, err = run_cli("grow", "-n", "200", "--model", "offlattice", "--dim", "3", "-o", tmp_path / "c.svg")
    assert status == 0, err
    text = (tmp_path / "c.svg").read_text()
    assert "<svg" in text and "<image" not in text and text.count("<use") >= 3 * 2 * 200  # a body and a cap each
    status, _, err = run_cli("grow", "-n", "200", "-o", tmp_path / "l.svg")
    assert status == 0, err
    assert "<image" in (tmp_path / "l.svg").read_text()  # the lattice: its image, a pixel per site or more


@pytest.mark.parametrize("dim", [2, 3])
def test_sites_placed_a_chunk_at_a_time_show_as_placed_at_once(dim, monkeypatch, tmp_path):
    """The lattice image is built a chunk of sites at a time (10^8 sites in bounded memory): a pixel
    shared across chunks still shows its nearest, then last attached, site."""
    import dlasweep.reporting.pictures as pictures

    c = dla.grow(20000 if dim == 2 else 3000, seed=5, dim=dim)
    draw_cluster(c.points, c.params, tmp_path / "whole.png", dpi=34)
    monkeypatch.setattr(pictures, "SITE_CHUNK", 777)
    draw_cluster(c.points, c.params, tmp_path / "chunks.png", dpi=34)
    whole, chunks = imread(tmp_path / "whole.png"), imread(tmp_path / "chunks.png")
    assert len(np.unique(whole.reshape(-1, whole.shape[-1]), axis=0)) > 50  # the sites' colours, many per pixel
    np.testing.assert_array_equal(whole, chunks)


@pytest.mark.parametrize("dim", [2, 3])
def test_disks_below_a_pixel_are_drawn_as_blocks_and_larger_ones_as_disks(dim):
    """Off the lattice, a picture whose pixels are wider than a disk shows a pixel per block of centres,
    as for sites (a 1e8 cluster in bounded memory); with disks of a pixel or more, every disk."""
    import matplotlib.pyplot as plt

    c = dla.grow(20000 if dim == 2 else 3000, seed=5, model="offlattice", dim=dim)
    for inches, blocks in ((1.0 if dim == 2 else 0.3, True), (12.0, False)):
        fig, ax = plt.subplots(figsize=(inches, inches), dpi=100)
        draw_points(ax, c.points, False, inches, view=(0, 1))
        assert bool(ax.images) == blocks and bool(ax.collections) != blocks
        if blocks:
            image = ax.images[0]
            x0, x1, y0, _ = image.get_extent()
            shown = image.get_array()[..., 3] > 0
            side = (x1 - x0) / shown.shape[1]
            centres = np.zeros_like(shown)
            centres[((c.points[:, 1] - y0) // side).astype(int), ((c.points[:, 0] - x0) // side).astype(int)] = True
            np.testing.assert_array_equal(shown, centres)  # a pixel is coloured where, and only where, a centre is
        plt.close(fig)

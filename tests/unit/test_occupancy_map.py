"""Building maps (ROS map_server format): read as Nav2 reads them, walls where the pixels say.

Every map is built here, in the test: PGM (binary and ASCII) and PNG files with header comments,
both ``negate`` values, the three modes and a non-zero origin.  Expected values follow Nav2's
``map_io.cpp`` (scenes/occupancy.py quotes it), computed by hand for each pixel.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely
from PIL import Image, PngImagePlugin
from scipy import ndimage

from agents.lib.socialmap.grid import GridSpec
from agents.lib.socialmap.occupancy import OccupancyLayer, dilate_disc
from agents.sim_robot.laser import Laser
from agents.world.building import FreeArea, scene_occupancy
from agents.world.navigation import PLANNING_MARGIN_M, NavigationMaps
from scenes.loader import load_scene
from scenes.occupancy import load_occupancy
from scenes.raster import cells_in_polygon
from scenes.yamlio import SourceError

ORIGIN = (-1.5, 2.0)


def write_pgm(path: Path, pixels: np.ndarray, ascii_: bool = False) -> None:
    """A PGM as map_saver writes it: comment lines in the header (and one between the fields)."""
    rows, cols = pixels.shape
    magic = "P2" if ascii_ else "P5"
    header = f"{magic}\n# CREATOR: test {0.5:.3f} m/pix\n{cols} {rows}\n# a second comment\n255\n"
    if ascii_:
        body = "\n".join(" ".join(str(int(v)) for v in row) for row in pixels).encode()
    else:
        body = pixels.astype(np.uint8).tobytes()
    path.write_bytes(header.encode() + body)


def write_yaml(path: Path, image: str, *, mode: str = "trinary", negate: int = 0, resolution: float = 0.5,
               origin: tuple[float, float] = ORIGIN, occupied: float = 0.65, free: float = 0.196,
               extra: str = "") -> Path:
    path.write_text(f"# map for a test\nimage: {image}\nmode: {mode}\nresolution: {resolution}\n"
                    f"origin: [{origin[0]}, {origin[1]}, 0.0]\nnegate: {negate}\n"
                    f"occupied_thresh: {occupied}\nfree_thresh: {free}\n{extra}")
    return path


# ------------------------------------------------------------------------------ reading, per mode
PIXELS = np.array([[0, 254, 205],
                   [100, 200, 254],
                   [37, 150, 255]], dtype=np.uint8)


def test_trinary_pgm_with_comments_and_origin(tmp_path: Path) -> None:
    write_pgm(tmp_path / "m.pgm", PIXELS)
    occupancy = load_occupancy(write_yaml(tmp_path / "m.yaml", "m.pgm"))
    # occ = 1 - p/255: 0 -> 1 (occupied), 254 -> 0.004 (free), 205 -> 0.196 (unknown: not < 0.196),
    # 100 -> 0.61 (unknown), 200 -> 0.216 (unknown), 37 -> 0.85 (occupied), 150 -> 0.41, 255 -> 0.
    expected_top_first = [[100, 0, -1], [-1, -1, 0], [100, -1, 0]]
    assert occupancy.values[::-1].tolist() == expected_top_first
    assert occupancy.extent == (-1.5, 2.0, 0.0, 3.5)
    # The image's top-left pixel is the cell at the map's top-left corner, in metres.
    assert occupancy.cell_of(-1.25, 3.25) == (2, 0) and occupancy.occupied[2, 0]
    assert occupancy.cell_of(-1.25, 2.25) == (0, 0) and occupancy.occupied[0, 0]      # pixel 37, bottom row
    assert occupancy.cell_of(-0.25, 2.25) == (0, 2) and not occupancy.blocked()[0, 2]  # pixel 255
    assert occupancy.cell_of(-1.6, 2.5) is None


def test_negate_swaps_black_and_white(tmp_path: Path) -> None:
    write_pgm(tmp_path / "m.pgm", PIXELS)
    occupancy = load_occupancy(write_yaml(tmp_path / "m.yaml", "m.pgm", negate=1))
    # occ = p/255: 0 free, 254 occupied, 205 (0.80) occupied, 100 (0.39) unknown, 37 (0.145) free.
    assert occupancy.values[::-1].tolist() == [[0, 100, 100], [-1, 100, 100], [0, -1, 100]]


def test_ascii_pgm_reads_like_binary(tmp_path: Path) -> None:
    write_pgm(tmp_path / "a.pgm", PIXELS, ascii_=True)
    write_pgm(tmp_path / "b.pgm", PIXELS)
    a = load_occupancy(write_yaml(tmp_path / "a.yaml", "a.pgm"))
    b = load_occupancy(write_yaml(tmp_path / "b.yaml", "b.pgm"))
    assert np.array_equal(a.values, b.values)


def test_scale_mode_png_with_alpha_and_comment(tmp_path: Path) -> None:
    grey = np.array([[0, 255, 128, 191]], dtype=np.uint8)
    alpha = np.array([[255, 255, 255, 0]], dtype=np.uint8)
    info = PngImagePlugin.PngInfo()
    info.add_text("Comment", "saved by a test")
    Image.fromarray(np.dstack([grey, alpha]), mode="LA").save(tmp_path / "m.png", pnginfo=info)
    occupancy = load_occupancy(write_yaml(tmp_path / "m.yaml", "m.png", mode="scale", occupied=0.65, free=0.25))
    # occ: 1 -> 100; 0 -> 0; 1 - 128/255 = 0.498 -> rint((0.498 - 0.25) / 0.4 * 100) = 62; transparent -> -1.
    assert occupancy.values.tolist() == [[100, 0, 62, -1]]


def test_trinary_averages_alpha_in(tmp_path: Path) -> None:
    """map_io: in trinary mode the alpha channel is averaged in with the colours."""
    rgba = np.array([[[255, 255, 255, 0], [255, 255, 255, 255], [0, 0, 0, 255]]], dtype=np.uint8)
    Image.fromarray(rgba, mode="RGBA").save(tmp_path / "m.png")
    occupancy = load_occupancy(write_yaml(tmp_path / "m.yaml", "m.png"))
    # shade (3 * 255 + 0) / 4 / 255 = 0.75 -> occ 0.25: unknown; opaque white free; opaque black occupied.
    assert occupancy.values.tolist() == [[-1, 0, 100]]


def test_raw_mode_keeps_values_up_to_100(tmp_path: Path) -> None:
    write_pgm(tmp_path / "m.pgm", np.array([[0, 37, 100, 101, 255]], dtype=np.uint8))
    occupancy = load_occupancy(write_yaml(tmp_path / "m.yaml", "m.pgm", mode="raw", negate=1))
    assert occupancy.values.tolist() == [[0, 37, 100, -1, -1]]   # negate and thresholds do not apply
    assert occupancy.occupied.tolist() == [[False, False, True, False, False]]


@pytest.mark.parametrize(("extra_yaml", "message", "line"), [
    ("", "no such image", 2),
    ("flavour: vanilla\n", "unknown key .flavour.", 9),
])
def test_bad_map_files_name_file_line_and_key(tmp_path: Path, extra_yaml: str, message: str, line: int) -> None:
    if "flavour" in extra_yaml:
        write_pgm(tmp_path / "m.pgm", PIXELS)
    path = write_yaml(tmp_path / "m.yaml", "m.pgm", extra=extra_yaml)
    with pytest.raises(SourceError, match=message) as info:
        load_occupancy(path)
    assert info.value.file == str(path) and info.value.line == line


def test_rotated_or_unreadable_maps_are_refused(tmp_path: Path) -> None:
    write_pgm(tmp_path / "m.pgm", PIXELS)
    path = write_yaml(tmp_path / "m.yaml", "m.pgm")
    path.write_text(path.read_text().replace("0.0]", "0.5]"))
    with pytest.raises(SourceError, match="unrotated map") as info:
        load_occupancy(path)
    assert info.value.key == "origin"
    (tmp_path / "junk.pgm").write_bytes(b"P5\nnot a header")
    with pytest.raises(SourceError, match="not a readable map image"):
        load_occupancy(write_yaml(tmp_path / "j.yaml", "junk.pgm"))
    write_pgm(tmp_path / "m.pgm", PIXELS)
    with pytest.raises(SourceError, match="free_thresh must be smaller"):
        load_occupancy(write_yaml(tmp_path / "t.yaml", "m.pgm", occupied=0.2, free=0.3))


# ------------------------------------------------------------------------------ a scene on a map
def ward_pixels(res: float = 0.05) -> np.ndarray:
    """8 m x 5 m at ``res``: outer walls 0.1 m, a wall at x = 4 m (from the map's left edge) with a
    1.2 m door at y 2..3.2 m; an unexplored 0.6 m square at x 1.5..2.1 m, y 3.5..4.1 m."""
    cols, rows = round(8 / res), round(5 / res)
    image = np.full((rows, cols), 254, dtype=np.uint8)
    t = round(0.1 / res)
    image[:t, :] = image[-t:, :] = image[:, :t] = image[:, -t:] = 0
    wall_col = round(4 / res)
    image[:, wall_col - t // 2 - 1:wall_col + 1] = 0
    image[rows - round(3.2 / res):rows - round(2.0 / res), wall_col - t // 2 - 1:wall_col + 1] = 254
    image[rows - round(4.1 / res):rows - round(3.5 / res), round(1.5 / res):round(2.1 / res)] = 205
    return image


SCENE = """name: on_a_map
map: {map}
rooms:
  - {{name: west, polygon: [[-1.5, 2.0], [2.5, 2.0], [2.5, 7.0], [-1.5, 7.0]]}}
  - {{name: east, polygon: [[2.5, 2.0], [6.5, 2.0], [6.5, 7.0], [2.5, 7.0]]}}
doors:
  - {{name: door, between: [west, east], position: [2.5, 4.6], width: 1.2}}
robot: {{pose: [0.0, 3.0, 0]}}
people:
{people}
missions:
  - {{id: m1, time: "09:30", goal: {{room: east}}}}
"""


def make_scene(tmp_path: Path, people: str = "  - {name: ann, pose: [5.0, 5.0, 3.14]}", map_ref: str = "maps/b.yaml",
               negate: int = 0, png: bool = False) -> Path:
    (tmp_path / "maps").mkdir(exist_ok=True)
    pixels = ward_pixels()
    if negate:
        pixels = 255 - pixels
    image = "b.png" if png else "b.pgm"
    if png:
        Image.fromarray(pixels).save(tmp_path / "maps" / image)
    else:
        write_pgm(tmp_path / "maps" / image, pixels)
    write_yaml(tmp_path / "maps" / "b.yaml", image, resolution=0.05, negate=negate)   # 205 (or 50) is unknown
    path = tmp_path / "scene.yaml"
    path.write_text(SCENE.format(map=map_ref, people=people))
    return path


@pytest.mark.parametrize(("negate", "png"), [(0, False), (1, True)])
def test_walls_land_on_the_right_metres(tmp_path: Path, negate: int, png: bool) -> None:
    scene = load_scene(make_scene(tmp_path, negate=negate, png=png)).scene
    assert scene.bounds == (-1.5, 2.0, 6.5, 7.0) and scene.resolution == 0.05
    maps = NavigationMaps.for_scene(scene)
    static = maps.static()
    spec = static.spec
    assert (spec.x0, spec.y0, spec.rows, spec.cols) == (-1.5, 2.0, 100, 160)   # the map's cells, one for one
    # The inner wall spans x 2.40..2.55 (pixels 78..80): its cells and the door's are where they should be.
    reach = scene.robot.radius + PLANNING_MARGIN_M
    for y in (2.5, 3.5, 6.0):
        assert not np.isfinite(static.grid[spec.cell_of(2.475, y)])
    assert np.isfinite(static.grid[spec.cell_of(2.475, 4.6)])                 # the door's middle
    # Inflation: a cell is blocked iff its centre is within reach + res/2 of a wall cell's centre.
    row = spec.cell_of(0.0, 3.0)[0]     # below the door: the nearest wall cells are the inner wall's
    xs = spec.xs()
    wall_x = 2.425       # centre of the westmost wall cell of the inner wall
    for col in np.nonzero((xs > 0.5) & (xs < wall_x))[0]:
        blocked = wall_x - xs[col] <= reach + 0.025 + 1e-9
        assert np.isfinite(static.grid[row, col]) != blocked, xs[col]
    # The unexplored square (unknown: wall by default) is blocked; with `unknown: free` it is floor.
    corner = spec.cell_of(0.3, 5.8)
    assert not np.isfinite(static.grid[corner])
    free_path = make_scene(tmp_path, map_ref="{file: maps/b.yaml, unknown: free}", negate=negate, png=png)
    floor = NavigationMaps.for_scene(load_scene(free_path).scene).static()
    assert np.isfinite(floor.grid[corner])


def test_scene_check_refuses_people_and_rooms_on_walls(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from tools.cli import app

    path = make_scene(tmp_path, people="  - {name: ann, pose: [2.45, 3.0, 0]}")
    result = CliRunner().invoke(app, ["scene", "check", str(path)])
    assert result.exit_code == 1
    assert "people[0].pose: person 'ann' at (2.45, 3) is on an occupied cell of the map: the cell centred at " \
           "(2.475, 3.025) m, pixel (79, 79) of b.pgm" in result.output
    path = make_scene(tmp_path, people="  - {name: ann, pose: [0.3, 5.8, 0]}")
    with pytest.raises(SourceError, match=r"on an unknown cell of the map.*unknown: free"):
        load_scene(path)
    walker = ("  - name: bob\n    pose: [1.0, 3.0, 0]\n    waypoints:\n"
              "      - {time: '10:00', pose: [1.0, 3.0, 0]}\n      - {time: '10:01', pose: [5.0, 3.0, 0]}")
    with pytest.raises(SourceError, match=r"'bob' would walk through an occupied cell .*\(2\.4\d\d, 3\.025\)") as info:
        load_scene(make_scene(tmp_path, people=walker))
    assert info.value.key == "people[0].waypoints[1]"   # the leg that ends at waypoint 1
    # A room drawn beyond the map, and one drawn over a wall.
    text = make_scene(tmp_path).read_text()
    (tmp_path / "beyond.yaml").write_text(text.replace("[6.5, 2.0], [6.5, 7.0]", "[7.5, 2.0], [7.5, 7.0]"))
    with pytest.raises(SourceError, match="reaches beyond the map"):
        load_scene(tmp_path / "beyond.yaml")
    (tmp_path / "wall.yaml").write_text(text.replace(
        "rooms:\n", "rooms:\n  - {name: in_wall, polygon: [[2.41, 2.2], [2.54, 2.2], [2.54, 4.0], [2.41, 4.0]]}\n"))
    with pytest.raises(SourceError, match=r"room 'in_wall' lies on walls of the map: 100% of its cells") as info:
        load_scene(tmp_path / "wall.yaml")
    assert info.value.key == "rooms[0].polygon"
    (tmp_path / "res.yaml").write_text("resolution: 0.1\n" + text)
    with pytest.raises(SourceError, match="resolution must be 0.05"):
        load_scene(tmp_path / "res.yaml")
    (tmp_path / "nomap.yaml").write_text(text.replace("maps/b.yaml", "maps/none.yaml"))
    with pytest.raises(SourceError, match="map file 'maps/none.yaml' not found") as info:
        load_scene(tmp_path / "nomap.yaml")
    assert info.value.line == 2


def test_laser_bumper_and_free_space_see_the_map(tmp_path: Path) -> None:
    scene = load_scene(make_scene(tmp_path)).scene
    layer = scene_occupancy(scene)
    assert layer is not None
    # From (0, 3) looking east, the inner wall's face is at x = 2.40 (the first wall pixel's edge).
    laser = Laser(np.empty((0, 4)), n_rays=3, max_range=8.0, fov=math.pi / 2, occupancy=layer)
    ranges = laser.scan(0.0, 3.0, 0.0, np.empty((0, 2)))
    assert ranges[1] == pytest.approx(2.40, abs=1e-9)
    # 45 degrees to the right the ray meets the bottom wall's face (y = 2.10) after 0.9 * sqrt(2) m.
    assert ranges[0] == pytest.approx(0.9 * math.sqrt(2), abs=1e-9)
    assert laser.scan(0.0, 4.6, 0.0, np.empty((0, 2)))[1] == pytest.approx(6.4, abs=1e-9)   # through the door
    assert Laser(np.empty((0, 4)), 3, 5.0, math.pi / 2, occupancy=layer).scan(0.0, 4.6, 0.0, np.empty((0, 2)))[1] == 5.0
    assert layer.clearance(2.0, 3.0, reach_m=1.0) == pytest.approx(0.40, abs=1e-9)
    assert layer.clearance(0.0, 4.6, reach_m=0.5) == math.inf
    free = FreeArea(scene, [], clearance_m=0.5)
    assert free.contains(0.0, 4.0) and not free.contains(2.0, 4.0) and not free.contains(2.9, 3.0)


def test_path_never_crosses_an_occupied_cell(tmp_path: Path) -> None:
    import json

    from typer.testing import CliRunner

    from tools.cli import app

    path = make_scene(tmp_path)
    result = CliRunner().invoke(app, ["path", str(path), "--at", "09:30", "--from", "0,3", "--to", "5,3", "--json"])
    assert result.exit_code == 0, result.output
    points = np.array(json.loads(result.stdout)["points"])
    occupancy = load_scene(path).scene.occupancy
    dense = np.vstack([a + (b - a) * f for a, b in zip(points[:-1], points[1:], strict=True)
                       for f in np.linspace(0, 1, 20)])
    cells = [occupancy.cell_of(x, y) for x, y in dense]
    assert all(cell is not None and not occupancy.blocked()[cell] for cell in cells)
    layer = scene_occupancy(load_scene(path).scene)
    assert min(layer.clearance(x, y, 1.0) for x, y in dense) >= 0.3   # the body never touches a wall
    assert any(abs(x - 2.475) < 0.05 and 4.0 < y < 5.2 for x, y in dense), "it goes through the door"


# ------------------------------------------------------------------------------ the grid helpers
def test_disc_dilation_equals_the_distance_rule() -> None:
    rng = np.random.default_rng(3)
    for radius in (0.5, 1.0, 2.3, 6.5, 9.5):
        mask = rng.random((60, 80)) < 0.01
        expected = ndimage.distance_transform_edt(~mask) <= radius
        assert np.array_equal(dilate_disc(mask, radius), expected), radius


def test_scan_line_raster_equals_shapely() -> None:
    rng = np.random.default_rng(5)
    res = 0.05
    xs, ys = -1 + (np.arange(90) + 0.5) * res, -0.5 + (np.arange(70) + 0.5) * res
    for trial in range(60):
        if trial % 2:   # vertices on cell centres, edges along rows and columns of centres
            polygon = shapely.Polygon((rng.integers(0, 70, (7, 2)) + 0.5) * res + (-1, -0.5)).buffer(0)
        else:
            polygon = shapely.union_all([shapely.Polygon(rng.uniform(-1.2, 3.6, (6, 2))).buffer(0),
                                         shapely.box(0.0, 0.0, 1.0, 1.0)]).difference(shapely.Point(2, 1).buffer(0.4))
        assert np.array_equal(cells_in_polygon(polygon, xs, ys),
                              shapely.intersects_xy(polygon, xs[None, :], ys[:, None])), polygon.wkt


def test_occupancy_layer_on_another_grid_samples_cell_centres() -> None:
    spec = GridSpec(0.0, 0.0, 0.1, 10, 10)
    blocked = np.zeros((10, 10), dtype=bool)
    blocked[4, 6] = True
    layer = OccupancyLayer(spec, blocked, outside_blocked=True)
    finer = GridSpec(-0.1, 0.0, 0.05, 20, 24)
    sampled = layer.sample(blocked, finer)
    assert sampled[:, 0].all() and sampled[:, 1].all()          # outside the map: blocked
    assert sampled[:, 22:].all()                                 # beyond x = 1.0 too
    assert sampled[8:10, 14:16].all() and sampled.sum() == 4 * 20 + 4


# ------------------------------------------------------------------------------ fuzzing map files
from hypothesis import given  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from tests.unit.fuzz_mutations import fuzz_settings, mutated_bytes  # noqa: E402


@fuzz_settings(120)
@given(data=st.data())
def test_mutated_map_files_give_located_errors(tmp_path_factory: pytest.TempPathFactory, data: st.DataObject) -> None:
    """Whatever the yaml or the image holds, loading answers with a map or a SourceError naming it."""
    folder = tmp_path_factory.mktemp("fuzz_map")
    write_pgm(folder / "m.pgm", ward_pixels(0.25))
    text = write_yaml(folder / "m.yaml", "m.pgm").read_text()
    if data.draw(st.booleans(), label="mutate the image"):
        pgm = (folder / "m.pgm").read_bytes()
        cut = data.draw(st.integers(0, len(pgm)), label="cut")
        junk = data.draw(st.binary(max_size=40), label="junk")
        (folder / "m.pgm").write_bytes(pgm[:cut] + junk + pgm[cut + len(junk):])
    else:
        (folder / "m.yaml").write_bytes(data.draw(mutated_bytes(text), label="yaml"))
    try:
        occupancy = load_occupancy(folder / "m.yaml")
    except SourceError as exc:
        assert exc.line >= 1 and exc.message.strip() and Path(exc.file).parent == folder, exc
    else:
        assert occupancy.values.dtype == np.int8 and occupancy.values.ndim == 2

"""`chronav scene from-map` and `chronav map export`, run as a user runs them (typer's CliRunner)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import shapely
import yaml
from scipy import ndimage
from typer.testing import CliRunner

from agents.lib.socialmap.nav2 import MaskScale, costs_from_keepout, social_costs, speed_values
from agents.world.offline import SceneMaps
from scenes.clock import parse_clock
from scenes.occupancy import load_occupancy
from tools.cli import app

RES = 0.05


def building_map(folder: Path) -> Path:
    """12 m x 9 m, origin (3, -2): a 2.4 m corridor along the south, two rooms north of it with a
    1.0 m door each, and a 1.1 m door between the rooms (a PGM with a comment, unknown margin)."""
    rows, cols = round(9 / RES), round(12 / RES)
    image = np.full((rows, cols), 205, dtype=np.uint8)

    def box(x0: float, y0: float, x1: float, y1: float, value: int) -> None:
        image[rows - round(y1 / RES):rows - round(y0 / RES), round(x0 / RES):round(x1 / RES)] = value

    box(0.4, 0.4, 11.6, 8.6, 0)            # outer walls 0.1 m
    box(0.5, 0.5, 11.5, 2.9, 254)          # corridor y 0.5..2.9
    box(0.5, 3.0, 5.95, 8.5, 254)          # west room
    box(6.05, 3.0, 11.5, 8.5, 254)         # east room
    box(2.5, 2.85, 3.5, 3.05, 254)         # door corridor - west room
    box(8.5, 2.85, 9.5, 3.05, 254)         # door corridor - east room
    box(5.9, 5.0, 6.1, 6.1, 254)           # door west - east
    header = f"P5\n# CREATOR: test_map_cli {RES:.3f} m/pix\n{cols} {rows}\n255\n".encode()
    (folder / "floor.pgm").write_bytes(header + image.tobytes())
    path = folder / "floor.yaml"
    path.write_text("image: floor.pgm\nmode: trinary\nresolution: 0.05\norigin: [3.0, -2.0, 0.0]\nnegate: 0\n"
                    "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    return path


def most_open_point(map_path: Path, polygon: list[list[float]]) -> tuple[float, float]:
    occupancy = load_occupancy(map_path)
    distance = ndimage.distance_transform_edt(~occupancy.blocked())
    xs = occupancy.x0 + (np.arange(occupancy.cols) + 0.5) * RES
    ys = occupancy.y0 + (np.arange(occupancy.rows) + 0.5) * RES
    inside = shapely.contains_xy(shapely.Polygon(polygon), xs[None, :], ys[:, None])
    row, col = np.unravel_index(np.argmax(np.where(inside, distance, -1)), distance.shape)
    return float(xs[col]), float(ys[row])


def test_scene_from_map_passes_the_check_and_plans_between_rooms(tmp_path: Path) -> None:
    (tmp_path / "maps").mkdir()
    map_path = building_map(tmp_path / "maps")
    out = tmp_path / "scenes" / "floor.yaml"
    runner = CliRunner()
    result = runner.invoke(app, ["scene", "from-map", str(map_path), "--out", str(out), "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert len(summary["rooms"]) == 3 and len(summary["doors"]) == 3, summary
    text = out.read_text()
    assert "map: ../maps/floor.yaml\n" in text and "# - name: tv" in text and "# - {id: serious_game" in text

    check = runner.invoke(app, ["scene", "check", str(out)])
    assert check.exit_code == 0, check.output

    scene = yaml.safe_load(text)
    rooms = {room["name"]: room["polygon"] for room in scene["rooms"]}
    # The two rooms north of the corridor (map-local (3, 5.5) and (9, 5.5), plus the origin).
    west_east = [next(name for name, polygon in rooms.items() if shapely.Polygon(polygon).contains(shapely.Point(x, 3.5)))
                 for x in (6.0, 12.0)]
    assert len(set(west_east)) == 2, rooms
    start, goal = (most_open_point(map_path, rooms[name]) for name in west_east)
    plan = runner.invoke(app, ["path", str(out), "--at", "09:30", "--from", f"{start[0]},{start[1]}",
                               "--to", f"{goal[0]},{goal[1]}", "--json"])
    assert plan.exit_code == 0, plan.output
    points = np.array(json.loads(plan.stdout)["points"])
    door = next(d for d in scene["doors"] if set(d["between"]) == set(west_east))
    assert np.min(np.hypot(*(points - door["position"]).T)) < 0.15, "the short way is the door between them"
    assert abs(door["position"][0] - 9.0) < 0.1 and abs(door["width"] - 1.1) < 0.11

    again = runner.invoke(app, ["scene", "from-map", str(map_path), "--out", str(out)])
    assert again.exit_code == 2 and "--force" in again.output


def test_scene_from_map_of_rooms_inside_a_corridor_loop_passes_the_check(tmp_path: Path) -> None:
    """Regression: a corridor that runs round a block of rooms is one room whose outline is the
    building's; the doors on its inner walls were refused as 'not on the outline of room'."""
    from tools.scene.building_maps import large_floor

    large_floor(60.0, 40.0, 0.1).write(tmp_path / "floor_map.yaml")
    out = tmp_path / "floor.yaml"
    runner = CliRunner()
    result = runner.invoke(app, ["scene", "from-map", str(tmp_path / "floor_map.yaml"), "--out", str(out), "--json"])
    assert result.exit_code == 0, result.output
    scene = yaml.safe_load(out.read_text())
    rooms = {room["name"]: shapely.Polygon(room["polygon"]) for room in scene["rooms"]}
    assert any(rooms[name].exterior.distance(shapely.Point(door["position"])) > 1.0
               for door in scene["doors"] for name in door["between"]), "a door on a corridor's inner wall"
    check = runner.invoke(app, ["scene", "check", str(out)])
    assert check.exit_code == 0, check.output


def test_scene_from_map_explains_a_map_without_floor(tmp_path: Path) -> None:
    (tmp_path / "w.pgm").write_bytes(b"P5\n4 3\n255\n" + bytes(12))
    (tmp_path / "w.yaml").write_text("image: w.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                                     "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    result = CliRunner().invoke(app, ["scene", "from-map", str(tmp_path / "w.yaml"), "--out", str(tmp_path / "s.yaml")])
    assert result.exit_code == 1 and "no free cell" in result.output and "Traceback" not in result.output


def test_exported_masks_reload_to_the_same_costs(tmp_path: Path) -> None:
    out = tmp_path / "masks"
    result = CliRunner().invoke(app, ["map", "export", "map_ward", "--at", "09:50", "--until", "10:00", "--every", "5",
                                      "--out", str(out), "--json"])
    assert result.exit_code == 0, result.output
    index = json.loads(result.stdout)
    assert [s["time"] for s in index["slices"]] == ["09:50:00", "09:55:00", "10:00:00"]
    maps = SceneMaps.load("map_ward")
    ward = maps.world.scene.occupancy
    scale = MaskScale.for_params(maps.nav.params)
    previous = None
    for entry in index["slices"]:
        keepout = load_occupancy(out / entry["keepout"])
        # Aligned cell for cell with the scene's map.
        assert (keepout.x0, keepout.y0, keepout.resolution, keepout.values.shape) == \
               (ward.x0, ward.y0, ward.resolution, ward.values.shape)
        smap = maps.at(parse_clock(entry["time"]))
        expected = social_costs(smap)
        decoded = costs_from_keepout(keepout.values, scale)
        finite = np.isfinite(expected)
        assert np.array_equal(finite, np.isfinite(decoded))
        assert np.max(np.abs(decoded[finite] - expected[finite])) <= scale.multiplier / 2 + 1e-9
        for band in (1.0, 2.0, 4.0):         # free, social, personal: exactly
            assert np.all(decoded[expected == band] == pytest.approx(band, abs=1e-12))
        assert (expected == 2.0).any() and (expected == 4.0).any() and (~finite).any()
        # Where the building is floor, the mask is the navigation's own grid at that time.
        floor = np.isfinite(smap.static)
        assert np.allclose(decoded[floor & finite], smap.cost[floor & finite], atol=scale.multiplier / 2 + 1e-9)
        speed = load_occupancy(out / entry["speed"])
        assert np.array_equal(speed.values, speed_values(expected, scale))
        assert np.all(speed.values[expected == 2.0] == 50) and np.all(speed.values[expected == 1.0] == 0)
        filters = yaml.safe_load((out / entry["filters"]).read_text())
        assert filters["keepout_filter_info_server"]["ros__parameters"]["type"] == 0
        assert filters["speed_filter_mask_server"]["ros__parameters"]["yaml_filename"] == entry["speed"]
        if previous is not None:   # R(t) of the TV rises towards the 10:00 game: the masks differ
            assert not np.array_equal(previous, keepout.values)
        previous = keepout.values
    tv = index["slices"][-1]["objects"]["tv"]
    assert tv["active"] and tv["R"] == pytest.approx(3.5)


def test_export_rejects_bad_slices(tmp_path: Path) -> None:
    runner = CliRunner()
    result = runner.invoke(app, ["map", "export", "map_ward", "--at", "10:00", "--until", "11:00", "--out", str(tmp_path)])
    assert result.exit_code == 2 and "--every" in result.output
    result = runner.invoke(app, ["map", "export", "map_ward", "--at", "10:00", "--until", "09:00", "--every", "5",
                                 "--out", str(tmp_path)])
    assert result.exit_code == 2 and "--until" in result.output

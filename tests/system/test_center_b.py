"""Issue 5 acceptance (multi-process): a mission across three rooms completes, and an agenda change
in the middle of it makes the robot replan around the new activity, as the recording shows."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import shapely

from agents.lib.metrics.metrics import read_trajectory_csv
from agents.world.offline import SceneMaps
from scenes.clock import parse_clock
from tests.system.launch_helpers import launch_json
from tests.system.recording import load_store, strips_over_time, texts

pytestmark = pytest.mark.slow
CHANGE_S = parse_clock("10:00:15")


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> dict:
    return launch_json("center_b", tmp_path_factory.mktemp("center_b") / "launch.log")


def test_three_room_mission_completes(run: dict) -> None:
    assert run["returncode"] == 0 and run["missions"]["to_ot"]["state"] == "done", run
    store = load_store(Path(run["rrd"]))
    plan_events = [text for _, text in texts(store, "/events/executive") if "to_ot steps" in text]
    assert plan_events, "the executive logs the plan it issues"
    rooms = re.findall(r"r2=(\w+)", plan_events[0])
    assert rooms == ["corridor", "occupational_therapy"], plan_events[0]


def test_agenda_change_mid_mission_causes_a_replan(run: dict) -> None:
    store = load_store(Path(run["rrd"]))
    changes = [t for t, text in texts(store, "/events/agenda") if "table_extra" in text and "accepted" in text]
    assert changes and abs(changes[0] - CHANGE_S) < 1.0
    finished = float(run["missions"]["to_ot"]["finished_s"])
    replans = [t for t, text in texts(store, "/events/social_navigation") if "replanned" in text]
    assert any(CHANGE_S <= t < finished for t in replans), "no replan between the agenda change and arrival"

    table = SceneMaps.load("center_b").at(CHANGE_S).interaction_polygons()["ot_table"]
    paths = strips_over_time(store, "/world/decision/path")
    first = next(points for t, points in paths if t < CHANGE_S)
    after = [points for t, points in paths if CHANGE_S <= t <= finished]
    assert shapely.LineString(first).intersects(table), "before the change the short way crossed the table"
    assert after and not shapely.LineString(after[-1]).intersects(table)

    trajectory = read_trajectory_csv(Path(run["run_dir"]) / "trajectory.csv")
    driven = trajectory[trajectory[:, 0] >= CHANGE_S + 2.0]  # two sim seconds to replan and turn
    assert not shapely.LineString(driven[:, 1:3]).intersects(table)


def test_a_door_closing_mid_mission_makes_the_robot_go_round(tmp_path_factory: pytest.TempPathFactory) -> None:
    """The world diverges: the north door the robot was heading for closes; it replans via the south one."""
    from agents.world.building import door_segment
    from scenes.loader import SCENES_DIR, load_scene

    folder = tmp_path_factory.mktemp("door")
    scene = folder / "center_b_door.yaml"
    scene.write_text((SCENES_DIR / "center_b.yaml").read_text()
                     + '\ndoor_changes:\n  - {at: "10:00:25", door: door_ot_north, open: false}\n')
    run = launch_json(str(scene), folder / "launch.log")
    assert run["returncode"] == 0 and run["missions"]["to_ot"]["state"] == "done", run
    store = load_store(Path(run["rrd"]))
    assert any("door door_ot_north closed" in text for _, text in texts(store, "/events/sim_robot"))
    closed_s = parse_clock("10:00:25")
    assert any(closed_s <= t and "current path blocked" in text for t, text in texts(store, "/events/social_navigation"))
    leaf = shapely.LineString(door_segment(load_scene(scene).scene, "door_ot_north"))
    trajectory = read_trajectory_csv(Path(run["run_dir"]) / "trajectory.csv")
    after = trajectory[trajectory[:, 0] >= closed_s]
    assert not shapely.LineString(after[:, 1:3]).intersects(leaf), "the robot went through a closed door"

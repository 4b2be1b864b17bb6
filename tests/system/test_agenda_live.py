"""Issue 6 acceptance: staff add an activity from a terminal and the driving robot avoids it.

The whole system runs as processes (`run_system` in a launcher subprocess, every agent in its
own process group) on tests/data/agenda_live.yaml: the robot crosses the room along the strip in
front of the TV, with nothing on the agenda.  As soon as it drives, `chronav agenda add tv ...`
(a real subprocess, found through the run's connect.json) puts a game on the TV a few sim
minutes later, so the TV's R(t) rises at once.  Checked on the replicated graph, the executed
trajectory and the merged Rerun recording, not on anyone's stdout.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from agents.lib.socialmap.objects import object_geometry
from agents.world.dsr_readers import dsr_objects
from agents.world.offline import graph_at
from agents.world.scene_world import load_world
from dsr import ZenohSettings, join
from scenes.clock import format_clock
from tests.support import REPO_ROOT, ProcessGroup, wait_until
from tools.system.runs import read_connect_file

SCENE = REPO_ROOT / "tests" / "data" / "agenda_live.yaml"
RATE = 1.0                      # sim s per wall s while driving: the mission takes ~20 s wall
LEAD_MIN = 3                    # the game starts this many sim minutes after the robot sets off
NORTH_OF_CABINET_Y = 2.5        # the detour passes north of the cabinet (y 2.0-2.5)
LAUNCH = ("import sys; from pathlib import Path; from tools.launch import run_system; "
          "r = run_system(sys.argv[1], rate=float(sys.argv[2]), runs_dir=Path(sys.argv[3]), timeout_s=120); "
          "sys.exit(0 if r.ok else 1)")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


@contextmanager
def launched(procs: ProcessGroup, runs: Path, log: Path) -> Iterator[subprocess.Popen[bytes]]:
    """The launcher; on the way out it is stopped with Ctrl-C (it stops its agents and merges),
    and any agent it left behind is killed by the pids it wrote."""
    launcher = procs.spawn(["-c", LAUNCH, str(SCENE), str(RATE), str(runs)], env={"RERUN": "on"}, log_path=log)
    try:
        yield launcher
    finally:
        if launcher.poll() is None:
            os.killpg(launcher.pid, signal.SIGINT)
            try:
                launcher.wait(timeout=30)
            except subprocess.TimeoutExpired:
                pass
        for pids_file in runs.glob("*/pids.json"):
            for pid in json.loads(pids_file.read_text()).values():
                if isinstance(pid, int) and _alive(pid):
                    os.killpg(pid, signal.SIGKILL)


def _tv_space() -> shapely.Polygon:
    world = load_world(SCENE)
    (tv,) = [o for o in dsr_objects(graph_at(world, world.scene.clock.start_s)) if o.name == "tv"]
    return object_geometry(tv).interaction


def _inside(space: shapely.Polygon, xy: np.ndarray) -> np.ndarray:
    return shapely.contains_xy(space, xy[:, 0], xy[:, 1])


def _active_intention(graph: Any) -> Any:
    return next((n for n in graph.nodes_of_type("intention")
                 if n.attrs.get("state") == "active" and n.attrs.get("kind") == "navigate"), None)


def _rows(store: Any, entity: str, component: str) -> list[tuple[float, Any]]:
    """(sim time in s, value) of every row logging ``entity:component`` in a merged recording."""
    table = store.reader(index="sim_time", contents=entity).to_arrow_table()
    times = table.column("sim_time").to_pylist()
    values = table.column(f"{entity}:{component}").to_pylist()
    return [(t.total_seconds(), v) for t, v in zip(times, values, strict=True) if v is not None]


def _texts(store: Any, entity: str) -> list[tuple[float, str]]:
    return [(t, text) for t, texts in _rows(store, entity, "TextLog:text") for text in texts]


def test_added_activity_makes_the_driving_robot_go_round_the_tv(procs: ProcessGroup, tmp_path: Path) -> None:
    runs = tmp_path / "recordings"
    space = _tv_space()
    with launched(procs, runs, tmp_path / "launcher.log") as launcher:
        wait_until(lambda: any(runs.glob("*/connect.json")) or launcher.poll() is not None, 30,
                   message="connect.json of the run")
        assert launcher.poll() is None, (tmp_path / "launcher.log").read_text()
        run_dir = next(runs.glob("*/connect.json")).parent
        run = read_connect_file(run_dir)        # the run's reader identity: its router requires one
        reader = run.identity("reader")
        settings = ZenohSettings(connect=[run.endpoint], user=reader.user, password=reader.password)
        with join("agenda_live_test", graph=run.graph, settings=settings, read_only=True) as graph:
            def robot() -> Any:
                return graph.get_node_by_name("robot")

            wait_until(lambda: robot() is not None and robot().attrs.get("nav_active") is True
                       and _active_intention(graph) is not None and "path_x" in robot().attrs, 60,
                       message="the robot driving its mission")
            intention = _active_intention(graph)
            replans_before = int(intention.attrs.get("replans", 0))
            path_before = list(robot().attrs["path_x"])
            first_path = np.column_stack([robot().attrs["path_x"], robot().attrs["path_y"]])
            assert _inside(space, first_path).any() and first_path[:, 1].max() < 2.0, \
                "with nothing scheduled the robot takes the strip, across the TV's space"
            now_s = float(graph.get_node_by_name("clock").attrs["now_s"])
            start_s = (math.floor(now_s / 60) + LEAD_MIN) * 60
            start, end = format_clock(start_s)[:5], format_clock(start_s + 1800)[:5]
            activity_id = f"tv-{start.replace(':', '')}"

            tool = subprocess.run([sys.executable, "-m", "tools.cli", "agenda", "add", "tv", start, end,
                                   "--name", "Serious game", "--run", str(run_dir)],
                                  cwd=REPO_ROOT, capture_output=True, text=True, timeout=60,
                                  env={**os.environ, "RERUN": "off"})
            assert tool.returncode == 0, tool.stderr
            assert tool.stdout.startswith(f"accepted: add: {activity_id} tv {start}:00-{end}:00 upcoming"), tool.stdout

            wait_until(lambda: graph.get_node_by_name(f"activity/{activity_id}") is not None, 10,
                       message="the activity node")
            assert graph.get_node_by_name(f"activity/{activity_id}").attrs["object"] == "tv"

            def replanned() -> bool:
                node = graph.get_node(intention.id)
                return node is not None and int(node.attrs.get("replans", 0)) > replans_before
            wait_until(replanned, 30, message="the navigation agent replanning")
            pose = graph.world_pose(robot().id)
            new_path = np.column_stack([robot().attrs["path_x"], robot().attrs["path_y"]])
            assert not space.contains(shapely.Point(pose[0], pose[1])), f"replanned only inside the space at {pose}"
            assert list(robot().attrs["path_x"]) != path_before
            assert not _inside(space, new_path).any() and new_path[:, 1].max() > NORTH_OF_CABINET_Y
        from rerun.chunk import RrdReader  # imported while the robot drives: seconds on a busy machine

        launcher.wait(timeout=90)
    result = json.loads((run_dir / "result.json").read_text())
    assert launcher.returncode == 0 and result["ok"], result

    store = RrdReader(str(result["rrd"])).stream().collect()
    agenda_events = _texts(store, "/events/agenda")
    accepted = [t for t, text in agenda_events
                if f"accepted: add: {activity_id} tv {start}:00-{end}:00" in text and "chronav agenda (" in text]
    assert len(accepted) == 1, agenda_events
    accepted_s = accepted[0]

    trajectory = np.loadtxt(run_dir / "trajectory.csv", delimiter=",", skiprows=1)
    after = trajectory[trajectory[:, 0] >= accepted_s]
    assert len(after) > 50 and not _inside(space, after[:, 1:3]).any(), "the robot crossed the TV's space"
    assert after[:, 2].max() > NORTH_OF_CABINET_Y
    assert math.hypot(after[-1, 1] - 11.2, after[-1, 2] - 1.0) < 0.5

    strips = [(t, np.asarray(s[0], dtype=float))
              for t, s in _rows(store, "/world/decision/path", "LineStrips2D:strips") if s]   # [] = cleared
    new_paths = [xy for t, xy in strips if t >= accepted_s]
    assert new_paths and not _inside(space, new_paths[0]).any() and new_paths[0][:, 1].max() > NORTH_OF_CABINET_Y
    assert any(_inside(space, xy).any() for t, xy in strips if t < accepted_s), "the first path crossed the TV"
    assert any("path replanned" in text for _, text in _texts(store, "/events/social_navigation"))

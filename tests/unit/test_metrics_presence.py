"""People who come and go (replayed crowds) count in the metrics only while they are there.

Regression: ``read_people_csv`` held a person missing from people.csv at their nearest known
state, so a robot that drove past where a replayed person had stood before she left (or where one
would enter later) was "near" a ghost: minimum distance, intrusions, forces and HuNavSim's metrics
all counted people who were not in the plaza.  Here a from-crowd scene's people (the simulator's
own crowd, written to people.csv as the simulator writes it) meet a robot that waits where one
person will enter before she does, and parks where another stood after she left; ``chronav metrics``
must see neither ghost.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from agents.lib.crowd.model import Agenda
from agents.lib.metrics.metrics import read_people_csv
from agents.world.offline import scene_obstacles
from agents.world.people import new_crowd
from agents.world.scene_world import load_world
from scenes.clock import parse_clock
from tests.unit.test_crowd_replay import _walkers
from tests.unit.test_hunav_parity import GOAL, load, transcription
from tools.cli import app

runner = CliRunner()
DURATION_S = 15.6      # _walkers' 40 frames, 0.4 s apart


def _robot(rel: float) -> tuple[float, float, float]:
    """Waits 0.8 m south of w_2's entry (6, 0) while she is not there yet (she enters at 4 s), drives
    west, then north past the place w_3 stood until she left (7.6 s) and parks 0.6 m from it."""
    legs = [(0.0, 6.0, -0.8), (2.0, 6.0, -0.8), (6.0, 2.0, -0.8), (14.0, 2.0, 6.6), (DURATION_S, 2.0, 6.6)]
    for (t0, x0, y0), (t1, x1, y1) in zip(legs, legs[1:], strict=False):
        if rel <= t1:
            f = (rel - t0) / (t1 - t0)
            heading = math.atan2(y1 - y0, x1 - x0) if (x1, y1) != (x0, y0) else 0.0
            return x0 + f * (x1 - x0), y0 + f * (y1 - y0), heading
    return legs[-1][1], legs[-1][2], 0.0


def _run(tmp_path: Path) -> tuple[Path, Path, Path, float]:
    """A from-crowd plaza and a run's trajectory.csv and people.csv, written as the simulator writes
    them (agents/sim_robot/agent.py: people.csv holds the crowd's people at each robot sample)."""
    data = _walkers(tmp_path / "w.txt")
    scene = tmp_path / "plaza.yaml"
    made = runner.invoke(app, ["scene", "from-crowd", str(data), "--out", str(scene), "--missions", "0", "--force"])
    assert made.exit_code == 0, made.output
    world = load_world(scene)
    crowd = new_crowd(world)
    start = parse_clock(world.scene.recordings[0].start or "09:00")
    quiet = Agenda(version=0, appointments=())
    run = tmp_path / "run"
    run.mkdir()
    traj, people = ["t,x,y,theta"], ["t,name,role,x,y,theta,vx,vy,group"]
    for k in range(round(DURATION_S / 0.1) + 1):
        t = start + 0.1 * k
        crowd.advance(t, lambda _t: quiet, None)
        x, y, theta = _robot(0.1 * k)
        traj.append(f"{t:.3f},{x:.4f},{y:.4f},{theta:.5f}")
        people.extend(f"{t:.3f},{p.name},{p.role},{p.x:.4f},{p.y:.4f},{p.theta:.5f},{p.vx:.4f},{p.vy:.4f},{p.group}"
                      for p in crowd.at(t))
    (run / "trajectory.csv").write_text("\n".join(traj) + "\n", encoding="utf-8")
    (run / "people.csv").write_text("\n".join(people) + "\n", encoding="utf-8")
    return scene, run / "trajectory.csv", run / "people.csv", start


def test_a_person_is_in_the_tracks_only_between_their_first_and_last_row(tmp_path: Path) -> None:
    _, _, people, start = _run(tmp_path)
    tracks = read_people_csv(people)
    rel = tracks.times - start
    present = dict(zip(tracks.names, tracks.present.T, strict=True))
    assert present["w_1"].all()
    assert not present["w_2"][rel < 4.0 - 1e-6].any() and present["w_2"][rel > 4.0 + 1e-6].all()
    assert present["w_3"][rel < 7.6 - 1e-6].all() and not present["w_3"][rel > 7.6 + 1e-6].any()
    assert np.isnan(tracks.x[~tracks.present]).all()
    # between two samples a person is there only if there at both; beyond the file, nobody is
    between = tracks.at(np.array([start + 7.65, start + 3.95, start + 5.05, start - 1.0, start + 99.0]))
    w2, w3 = tracks.names.index("w_2"), tracks.names.index("w_3")
    assert not between.present[0, w3] and not between.present[1, w2] and between.present[2, w2]
    assert between.x[2, w2] == pytest.approx(6.0) and between.y[2, w2] == pytest.approx(1.05, abs=1e-3)
    assert not between.present[3:].any()


def test_chronav_metrics_counts_only_who_was_there(tmp_path: Path) -> None:
    """The published definitions against a brute-force reading of people.csv's rows (who has a row
    at a robot sample's time is there), and the ghosts the old reader made would be far nearer."""
    scene, traj, people, start = _run(tmp_path)
    result = runner.invoke(app, ["metrics", str(scene), str(traj), "--people", str(people), "--json"])
    assert result.exit_code == 0, result.output
    dyn = json.loads(result.stdout)["metrics"]["dynamic"]
    radius = load_world(scene).scene.robot.radius
    robot = {row.split(",")[0]: tuple(map(float, row.split(",")[1:3])) for row in traj.read_text().split()[1:]}
    closest: dict[str, float] = {}
    for row in people.read_text().split()[1:]:
        t, _name, _role, x, y = row.split(",")[:5]
        edge = max(0.0, math.dist(robot[t], (float(x), float(y))) - radius - 0.25)
        closest[t] = min(closest.get(t, math.inf), edge)
    assert dyn["min_distance_to_people_m"] == pytest.approx(min(closest.values()), abs=1e-9)
    assert dyn["avg_distance_to_closest_person_m"] == pytest.approx(float(np.mean(list(closest.values()))))
    # the ghosts: w_2 held at her entry while the robot waited 0.8 m from it, w_3 at her last place
    # while it parked 0.6 m from it (edges 0.25 m and 0.05 m); nobody who was there came near
    assert min(closest.values()) > 1.2
    assert dyn["intimate_intrusions_percent"] == dyn["personal_intrusions_percent"] == 0.0
    assert dyn["robot_intimate_entries"] == dyn["robot_on_person_collisions"] == 0
    for name in ("w_2", "w_3"):
        assert dyn["intrusions_per_person"][name]["intimate"] == dyn["intrusions_per_person"][name]["personal"] == 0.0


def test_hunav_definitions_match_the_transcription_when_people_come_and_go(tmp_path: Path) -> None:
    """HuNavSim's evaluator walks each sample's agents message: a person absent from a sample is
    not in it.  chronav's --definitions hunav against the transcription of test_hunav_parity."""
    scene, traj, people, _ = _run(tmp_path)
    result = runner.invoke(app, ["metrics", str(scene), str(traj), "--people", str(people), "--definitions", "hunav",
                                 "--goal", f"{GOAL[0]},{GOAL[1]}", "--json"])
    assert result.exit_code == 0, result.output
    ours = json.loads(result.stdout)["metrics"]
    robot, agents = load(traj.parent)
    assert any(not ags for ags in agents) is False and len({len(ags) for ags in agents}) > 1, \
        "people come and go over the run"
    theirs = transcription(robot, agents, scene_obstacles(load_world(scene).scene))
    for key, value in theirs.items():
        assert ours[key] == pytest.approx(value, rel=1e-6, abs=1e-6), key
    assert theirs["minimum_distance_to_people"] > 1.0 and theirs["intimate_space_intrusions"] == 0.0, "no ghost"

"""Recorded crowds: ``chronav scene from-crowd`` (the plaza, the missions, bad recordings named by
file and line) and ``routine: replay`` people in the crowd (exact: on their record whatever the
robot does; reactive: round the robot), through the scene check and an in-process run."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from agents.lib.crowd.model import Agenda, RobotBody
from agents.world.people import new_crowd
from agents.world.scene_world import load_world
from scenes.clock import parse_clock
from scenes.crowd_recording import read_recording
from tests.support import REPO_ROOT
from tools.cli import app

runner = CliRunner()
UNI = REPO_ROOT / "scenes" / "data" / "pedestrians" / "uni_examples.txt"


def _walkers(path: Path, frames: int = 40) -> Path:
    """Three people, frames 10 apart (0.4 s): a walks east across the middle, b walks north and
    enters late, c stands still for 20 frames then leaves the recording."""
    lines = []
    for k in range(frames):
        lines.append(f"{10 * k}\t1\t{0.3 * k:.4f}\t3.0")
        if k >= 10:
            lines.append(f"{10 * k}\t2\t6.0\t{0.4 * (k - 10):.4f}")
        if k < 20:
            lines.append(f"{10 * k}\t3\t2.0\t6.0")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _from_crowd(tmp_path: Path, *args: str) -> tuple[Path, object]:
    out = tmp_path / "plaza.yaml"
    result = runner.invoke(app, ["scene", "from-crowd", *args, "--out", str(out), "--force"])
    return out, result


@pytest.mark.parametrize(("content", "expected"), [
    ("0 1 2.0 3.0\n0 1 2.5 3.0\n", ":2: person 1 appears twice in frame 0"),
    ("10 1 2.0 3.0\n0 2 2.5 3.0\n", ":2: frame 0 comes after frame 10"),
    ("0 1 nan 3.0\n", ":1: a value is not a finite number"),
    ("0 1 2.0 3.0\n10 1 2.1 3.0\n10 2 5.0 5.0\n20 2 5.0 5.1\n30 1 2.2 3.0\n", ":5: person 1 reappears at frame 30"),
    ("0 1 2.0 x\n", ":1: 'frame id x y' must be numbers"),
    ("0 1 2.0\n", ":1: expected 4 columns"),
    ("", "no annotations"),
])
def test_a_bad_recording_is_named_with_its_file_and_line(tmp_path: Path, content: str, expected: str) -> None:
    bad = tmp_path / "bad.txt"
    bad.write_text(content, encoding="utf-8")
    _, result = _from_crowd(tmp_path, str(bad))
    assert result.exit_code == 2, result.output
    assert f"bad.txt{expected}" in result.stderr or (expected in result.stderr and "bad.txt" in result.stderr)
    assert "Traceback" not in result.output


def test_a_recording_beyond_the_documented_limits_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CHRONAV_LIMIT_CROWD_ROWS", "50")
    _, result = _from_crowd(tmp_path, str(_walkers(tmp_path / "w.txt")))
    assert result.exit_code == 2 and "w.txt:51: more than 50 annotations" in result.stderr
    assert "CHRONAV_LIMIT_CROWD_ROWS" in result.stderr
    monkeypatch.delenv("CHRONAV_LIMIT_CROWD_ROWS")
    monkeypatch.setenv("CHRONAV_LIMIT_CROWD_PEOPLE", "2")
    _, result = _from_crowd(tmp_path, str(_walkers(tmp_path / "w.txt")))
    assert result.exit_code == 2 and "more than 2 people" in result.stderr


def test_from_crowd_on_a_shipped_sequence_gives_a_checked_seeded_scene(tmp_path: Path) -> None:
    """The plaza holds every record with the margin; every person is a replayed one; missions leave
    from where the robot is and pass through a busy cell on the way to the far side; the same seed
    gives the same file, another seed other missions; `scene check` passes."""
    out, result = _from_crowd(tmp_path, str(UNI), "--missions", "3", "--seed", "4")
    assert result.exit_code == 0, result.output
    first = out.read_text(encoding="utf-8")
    assert runner.invoke(app, ["scene", "check", str(out)]).exit_code == 0
    world = load_world(out)
    scene = world.scene
    recording = read_recording(UNI)
    xmin, ymin, xmax, ymax = recording.extent()
    bx0, by0, bx1, by1 = scene.bounds
    assert bx0 <= xmin - 2.0 + 0.1 and by0 <= ymin - 2.0 + 0.1 and bx1 >= xmax + 2.0 - 0.1 and by1 >= ymax + 2.0 - 0.1
    assert len(scene.people) == len(recording.tracks) and {p.routine for p in scene.people} == {"replay"}
    assert len(scene.missions) == 3
    here = (scene.robot.pose.x, scene.robot.pose.y)
    for mission in scene.missions:
        goal = mission.goal.pose                   # type: ignore[union-attr]
        via = tuple(float(v) for v in mission.description.split("through (")[1].split(")")[0].split(", "))
        # the busy cell's centre lies on the straight crossing from here to the goal
        d = np.subtract((goal.x, goal.y), here)
        w = np.subtract(via, here)
        assert abs(d[0] * w[1] - d[1] * w[0]) / np.hypot(*d) < 0.05 and 0 < np.dot(w, d) <= np.dot(d, d)
        here = (goal.x, goal.y)
    again, _ = _from_crowd(tmp_path, str(UNI), "--missions", "3", "--seed", "4")
    assert again.read_text(encoding="utf-8") == first
    _from_crowd(tmp_path, str(UNI), "--missions", "3", "--seed", "5")
    assert out.read_text(encoding="utf-8") != first


def test_replay_exact_follows_the_record_and_people_come_and_go(tmp_path: Path) -> None:
    """Exact: each person at the record's interpolated point, present only from their first to
    their last annotation, whatever the robot does (it drives across a's path here)."""
    out, result = _from_crowd(tmp_path, str(_walkers(tmp_path / "w.txt")), "--missions", "0")
    assert result.exit_code == 0, result.output
    world = load_world(out)
    crowd = new_crowd(world)
    start = parse_clock(world.scene.recordings[0].start or "09:00")
    recording = read_recording(tmp_path / "w.txt")
    quiet = Agenda(version=0, appointments=())
    for t in np.arange(start - 1.0, start + 17.0, 0.35):
        robot = RobotBody(3.0, 3.0, 0.0, 0.3, 0.3)     # driving, right on a's line
        crowd.advance(float(t), lambda _t: quiet, robot)
        seen = {p.name: p for p in crowd.at(float(t))}
        for pid, track in recording.tracks.items():
            name = f"w_{pid}"
            rel = float(t) - start
            if track.start_s - 1e-6 <= rel <= track.end_s + 1e-6:
                x, y, vx, vy = track.at(rel)
                assert name in seen and math.hypot(seen[name].x - x, seen[name].y - y) < 1e-9
                assert (seen[name].vx, seen[name].vy) == pytest.approx((vx, vy))
            else:
                assert name not in seen, f"{name} is not in the scene at {rel:.2f} s"


def test_replay_reactive_goes_round_the_robot_and_keeps_to_its_record(tmp_path: Path) -> None:
    """Reactive: the robot stands on a's recorded line; a walks round it (never inside its body
    plus a person's) and is back near the record's end when it ends (exact: the test above)."""
    out, _ = _from_crowd(tmp_path, str(_walkers(tmp_path / "w.txt")), "--missions", "0", "--replay", "reactive")
    world = load_world(out)
    assert world.scene.crowd.replay == "reactive"
    crowd = new_crowd(world)
    start = parse_clock(world.scene.recordings[0].start or "09:00")
    quiet = Agenda(version=0, appointments=())
    robot = RobotBody(6.0, 3.0, 0.0, 0.0, 0.3)
    closest = math.inf
    last = None
    for t in np.arange(start, start + 15.6, 0.25):
        crowd.advance(float(t), lambda _t: quiet, robot)
        a = {p.name: p for p in crowd.at(float(t))}.get("w_1")
        if a is not None:
            closest = min(closest, math.hypot(a.x - robot.x, a.y - robot.y))
            last = a
    assert closest >= 0.3 + 0.25 - 0.02, closest
    assert last is not None and math.hypot(last.x - 0.3 * 39, last.y - 3.0) < 0.6


@pytest.mark.slow
def test_an_in_process_run_of_a_generated_scene_replays_the_record_exactly(tmp_path: Path) -> None:
    """The same path a user takes: from-crowd, then `chronav launch --in-process`; the run's
    people.csv holds each replayed person where the record puts them (within the csv's 4 decimals)
    and only while the record says they are there."""
    data = _walkers(tmp_path / "w.txt", frames=60)
    out, result = _from_crowd(tmp_path, str(data), "--missions", "1", "--seed", "1")
    assert result.exit_code == 0, result.output
    runs = tmp_path / "runs"
    launched = runner.invoke(app, ["launch", str(out), "--in-process", "--no-record", "--timeout", "120"],
                             env={"CHRONAV_RUNS": str(runs)})
    assert launched.exit_code == 0, launched.output
    people = next(runs.glob("*/people.csv"))
    prediction = json.loads(next(runs.glob("*/result.json")).read_text(encoding="utf-8"))["prediction"]
    assert prediction["predictions"] > 0 and 0 < prediction["ade_m"] < prediction["fde_m"], \
        "the observer's predictions of the replayed walkers, scored against people.csv"
    recording = read_recording(data)
    start = parse_clock(load_world(out).scene.recordings[0].start or "09:00")
    rows = list(csv.DictReader(people.open(encoding="utf-8")))
    assert rows, "the robot drove among the replayed people"
    for row in rows:
        track = recording.tracks[int(row["name"].split("_")[-1])]
        rel = float(row["t"]) - start
        assert track.start_s - 1e-3 <= rel <= track.end_s + 1e-3
        x, y, _, _ = track.at(rel)
        assert math.hypot(float(row["x"]) - x, float(row["y"]) - y) < 2e-3


def test_a_person_entering_where_another_left_gets_their_own_track() -> None:
    """Regression (corridor_counterflow): p4's record ended at the corridor's end; 1.2 s later p3
    entered there and walked off, and the tracker took p3's detections for p4 (inside p4's gate,
    only the name-mismatch cost against it), so "p4" walked away with p3.  A track missed for
    ASSOCIATE_S is now matched by its own name only."""
    from agents.lib.perception.tracking import Detection, observer_tracker

    tracker = observer_tracker(0.02)
    for k in range(30):                                   # p4 walks west, then stands at (1.0, 1.67) for 2 s
        tracker.update(0.1 * k, [Detection("p4", max(2.0 - 0.1 * k, 1.0), 1.67, 3.14)])
    for k in range(30):                                   # p4 has left; 1.2 s later p3 enters there, walks east
        tracker.update(4.1 + 0.1 * k, [Detection("p3", 1.0 + 0.11 * k, 1.67, 0.0)])
    assert "p3" in tracker.tracks and tracker.tracks["p3"].x > 3.5
    assert tracker.tracks["p4"].x < 1.5, "the gone person's track stays where they left"


def test_the_scene_check_refuses_a_record_outside_the_rooms_or_a_missing_track(tmp_path: Path) -> None:
    """Nobody is moved silently: a record that leaves the rooms, or a track the file does not
    hold, is refused at the person's line with the reason."""
    out, _ = _from_crowd(tmp_path, str(_walkers(tmp_path / "w.txt")), "--missions", "0")
    text = out.read_text(encoding="utf-8")
    narrow = tmp_path / "narrow.yaml"
    walls = text[text.index("walls:"):text.index("rooms:")]
    narrow.write_text(text.replace(walls, "walls:\n- [[-2, -2], [8, -2], [8, 8], [-2, 8], [-2, -2]]\n")
                      .replace(text[text.index("rooms:"):text.index("crowd:")],
                               "rooms:\n- name: plaza\n  polygon: [[-2, -2], [8, -2], [8, 8], [-2, 8]]\n"),
                      encoding="utf-8")
    result = runner.invoke(app, ["scene", "check", str(narrow)])
    assert result.exit_code != 0 and "'w_1' walks outside the scene's rooms at (8.10, 3.00)" in result.output
    assert "people[0].track" in result.output or "narrow.yaml:" in result.output
    missing = tmp_path / "missing.yaml"
    missing.write_text(text.replace("track: 3,", "track: 99,"), encoding="utf-8")
    result = runner.invoke(app, ["scene", "check", str(missing)])
    assert result.exit_code != 0 and "person 99 is not in recording 'w'" in result.output


def test_from_crowd_says_how_many_crossings_fit(tmp_path: Path) -> None:
    """A 16 s recording has room for one crossing only: --json reports the missions written."""
    out = tmp_path / "short.yaml"
    result = runner.invoke(app, ["scene", "from-crowd", str(_walkers(tmp_path / "w.txt")), "--out", str(out),
                                 "--missions", "3", "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["missions"] == len(load_world(out).scene.missions) == 1
    assert summary["people"] == 3 and summary["rows"] == 40 + 30 + 20


@pytest.mark.parametrize("noise", ["0", "0.02"])
def test_the_observer_forgets_a_person_who_left(noise: str) -> None:
    """A replayed person whose record ended is no longer in the simulator's truth: the observer
    drops their track (at once with a perfect sensor, after tracking.LOST_S with a noisy one) and
    their person node leaves the DSR, so the social map forgets them; the others stay."""
    from agents.lib.crowd.model import PersonTruth
    from agents.lib.perception.tracking import LOST_S
    from agents.runtime.recording import Recorder
    from agents.world.dsr_writers import write_building, write_ground_truth
    from dsr import DSRGraph
    from tools.inprocess import build_agents

    scene_path = REPO_ROOT / "scenes" / "crowds" / "perpendicular_crossing.yaml"
    observer = build_agents(scene_path, ["human_observer"], options={"human_observer": {"noise_xy": noise}})[0]
    graph = DSRGraph(agent="test_observer_leave")
    observer.setup(graph, Recorder("human_observer", None, None))
    write_building(graph, load_world(scene_path).scene, {})
    t0 = 32400.0
    for k in range(60):
        t = t0 + 0.1 * k
        people = [PersonTruth("p1", "visitor", 0.0, -6.0 + 1.0 * 0.1 * k, 1.57, 0.0, 1.0)]
        if k < 20:
            people.append(PersonTruth("p2", "visitor", 1.0, -6.0 + 1.0 * 0.1 * k, 1.57, 0.0, 1.0))
        write_ground_truth(graph, people, t)
        observer.step()
        if k == 19:
            assert graph.get_node_by_name("p2") is not None
    assert graph.get_node_by_name("p1") is not None
    assert graph.get_node_by_name("p2") is None, f"p2 left {4.0:g} s ago (> {LOST_S:g} s)"


def test_from_crowd_dt_sets_the_recordings_time_step(tmp_path: Path) -> None:
    """--dt is the seconds per annotated frame step: 0.8 s makes the same 40 frames last twice as long."""
    data = _walkers(tmp_path / "w.txt")
    durations = []
    for dt in ("0.4", "0.8"):
        out = tmp_path / f"dt{dt.replace('.', '_')}.yaml"
        result = runner.invoke(app, ["scene", "from-crowd", str(data), "--out", str(out), "--dt", dt, "--json"])
        assert result.exit_code == 0, result.output
        durations.append(json.loads(result.stdout)["duration_s"])
        assert load_world(out).scene.recordings[0].dt == float(dt)
    assert durations == [pytest.approx(15.6), pytest.approx(31.2)]
    bad = runner.invoke(app, ["scene", "from-crowd", str(data), "--out", str(tmp_path / "x.yaml"), "--dt", "0"])
    assert bad.exit_code == 2 and "--dt" in bad.output

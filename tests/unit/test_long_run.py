"""Runs that span days (issue 41): each day's agenda, missions and scripted changes, the per-day
accounting of result.json, the index of day recordings, retention, bad days and a full disk.

The runs are in-process on tests/data/week_tiny.yaml (two days of one room, a few seconds), through
`chronav launch` as a user types it."""

from __future__ import annotations

import csv
import datetime as dt
import errno
import json
import math
import os
from pathlib import Path
from types import SimpleNamespace

import pytest
from typer.testing import CliRunner

from agents.world.scene_world import load_world, resolve_world
from scenes.days import day_scene_data, on_day, parse_weekday, week_seconds
from scenes.loader import load_scene
from scenes.yamlio import SourceError
from tests.support import recording_entities
from tools.cli import app
from tools.week_index import read_index, recording_of_day

WEEK = Path(__file__).resolve().parents[1] / "data" / "week_tiny.yaml"


def _variant(tmp_path: Path, *, days: int, extra_agenda: str = "", extra_missions: str = "") -> Path:
    """week_tiny with more days and more lines in its agenda and missions."""
    text = WEEK.read_text().replace("days: 2,", f"days: {days},")
    text = text.replace("\nagenda_changes:", f"{extra_agenda}\nagenda_changes:")
    text = text.rstrip("\n") + "\n" + extra_missions
    path = tmp_path / "week_variant.yaml"
    path.write_text(text)
    return path


def test_days_of_the_week_and_the_week_clock() -> None:
    assert parse_weekday("Monday") == "mon" and parse_weekday("TUE") == "tue"
    with pytest.raises(ValueError, match="not a day of the week"):
        parse_weekday("lunes")
    tuesday = dt.date(2026, 12, 1)
    assert on_day([], [], tuesday) and on_day(["tue"], [], tuesday) and not on_day(["mon"], [], tuesday)
    assert on_day(["mon"], [tuesday], tuesday)
    assert week_seconds(1, 9 * 3600) == 86400 + 32400


def test_each_day_has_the_agenda_missions_and_changes_of_its_date() -> None:
    loaded = load_scene(WEEK)
    monday = day_scene_data(loaded.located.data, 1, WEEK.parent, first=loaded.scene.clock.date)
    tuesday = day_scene_data(loaded.located.data, 2, WEEK.parent, first=loaded.scene.clock.date, seed_offset=1)
    assert [a["id"] for a in monday["agenda"]] == ["game"] and [m["id"] for m in monday["missions"]] == ["cross", "dock"]
    assert monday["agenda_changes"] == [] and tuesday["agenda_changes"][0]["id"] == "music"
    assert [a["id"] for a in tuesday["agenda"]] == ["music"] and [m["id"] for m in tuesday["missions"]] == ["back", "dock"]
    assert tuesday["clock"]["date"] == dt.date(2026, 12, 1) and "days" not in tuesday["clock"]
    assert tuesday["crowd"]["seed"] == 1 and "weekdays" not in tuesday["agenda"][0]
    # The scene placed on its second day: Tuesday's agenda, the change that names day 2.
    world = resolve_world(loaded, 2)
    assert [a.id for a in world.agenda.activities] == ["music"] and len(world.scripted) == 1
    assert [a.id for a in load_world(WEEK).agenda.activities] == ["game"] and load_world(WEEK).scripted == ()


def test_a_change_on_a_day_the_scene_does_not_have_is_located(tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(WEEK.read_text().replace("day: 2, op: move", "day: 5, op: move"))
    with pytest.raises(SourceError) as caught:
        load_scene(path)
    assert caught.value.key == "agenda_changes[0].day" and "spans 2 days" in caught.value.message


def test_scene_check_checks_every_day_and_names_the_bad_one(tmp_path: Path) -> None:
    bad = _variant(tmp_path, days=2, extra_agenda='\n  - {id: piano_class, name: Piano, object: piano, start: "09:00", '
                                                  'end: "09:30", dates: [2026-12-01]}')
    result = CliRunner().invoke(app, ["scene", "check", str(bad)])
    assert result.exit_code == 1
    assert "piano" in result.output and "(on day 2, tue 2026-12-01)" in result.output


def test_two_days_in_process_leave_a_day_each_and_their_accounting(tmp_path: Path,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CHRONAV_RUNS", str(tmp_path / "runs"))
    monkeypatch.setenv("RERUN", "on")
    result = CliRunner().invoke(app, ["launch", str(WEEK), "--in-process", "--json", "--keep-days", "1"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["ok"] and summary["days_planned"] == 2 and summary["restarts_total"] == 0
    monday, tuesday = summary["days"]
    assert (monday["weekday"], tuesday["weekday"], tuesday["offset_s"]) == ("mon", "tue", 86400.0)
    assert list(monday["missions"]) == ["cross", "dock"] and list(tuesday["missions"]) == ["back", "dock"]
    assert tuesday["missions"]["back"]["state"] == "done" and tuesday["missions_summary"]["done"] == 2
    for day in (monday, tuesday):
        assert day["agents"]["in_process"]["rss_mb"] > 0 and day["agents"]["in_process"]["cpu_s"] > 0
        assert day["dsr"]["nodes"] > 0 and day["dsr"]["edges"] > 0 and day["dsr"]["tombstones"] >= 0
        assert day["bytes_written"] >= day["rrd_bytes"] > 0 and day["metrics"]["path_length_m"] > 0
    # Day 2 ran Tuesday's agenda: its own scene holds the music session and the change naming day 2.
    run_dir = Path(summary["run_dir"])
    tuesday_world = load_world(run_dir / "days" / "day2.yaml")
    assert [a.id for a in tuesday_world.agenda.activities] == ["music"] and len(tuesday_world.scripted) == 1
    # One recording per day; --keep-days 1 removed Monday's files but kept its accounting.
    index = read_index(Path(summary["index"]))
    assert [e["status"] for e in index["entries"]] == ["ok", "ok"] and index["entries"][0].get("removed")
    assert monday["removed"] and monday["rrd"] is None and tuesday["rrd"]
    assert recording_of_day(Path(summary["index"]), None) == run_dir / tuesday["rrd"]
    assert len(list(run_dir.glob("*.rrd"))) == 1
    assert [p.name for p in run_dir.iterdir() if p.is_dir() and p.name != "days"] == [tuesday["run_dir"]]
    # Each day ends with the robot back at its dock for the night (the scene's robot pose).
    assert monday["missions"]["dock"]["state"] == tuesday["missions"]["dock"]["state"] == "done"
    assert tuesday["missions"]["dock"]["started_s"] >= tuesday["missions"]["back"]["finished_s"]
    with (run_dir / tuesday["run_dir"] / "trajectory.csv").open() as handle:
        last = list(csv.DictReader(handle))[-1]
    assert math.dist((float(last["x"]), float(last["y"])), (0.8, 1.2)) < 0.5, last


def test_a_day_whose_agenda_cannot_be_loaded_is_refused_and_the_run_goes_on(tmp_path: Path,
                                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CHRONAV_RUNS", str(tmp_path / "runs"))
    scene = _variant(tmp_path, days=3,
                     extra_agenda='\n  - {id: piano_class, name: Piano, object: piano, start: "09:00", end: "09:30", '
                                  'dates: [2026-12-01]}',
                     extra_missions='  - {id: wed_cross, time: "09:10", goal: {pose: [5.2, 1.2, 0]}, weekdays: [wed]}\n')
    result = CliRunner().invoke(app, ["launch", str(scene), "--in-process", "--json", "--no-record"])
    assert result.exit_code == 1, result.output
    summary = json.loads(result.stdout)
    assert [d["status"] for d in summary["days"]] == ["ok", "refused", "ok"]
    assert "piano" in summary["days"][1]["reason"] and "on day 2" in summary["days"][1]["reason"]
    assert summary["days"][2]["missions"]["wed_cross"]["state"] == "done"


def test_a_disk_that_fills_while_rotating_ends_the_run_cleanly(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CHRONAV_RUNS", str(tmp_path / "runs"))
    replace = os.replace

    def full_disk(src: str, dst: str) -> None:
        if str(dst).endswith("day2.yaml"):
            raise OSError(errno.ENOSPC, "No space left on device")
        replace(src, dst)

    monkeypatch.setattr("tools.week_index.os.replace", full_disk)
    result = CliRunner().invoke(app, ["launch", str(WEEK), "--in-process", "--json", "--no-record"])
    assert result.exit_code == 1
    summary = json.loads(result.stdout)
    assert "the disk is full" in summary["error"] and "day2.yaml" in summary["error"]
    assert [d["day"] for d in summary["days"]] == [1] and summary["outcome"] == "error"
    run_dir = Path(summary["run_dir"])
    assert not list(run_dir.rglob("*.tmp")) and not (run_dir / "days" / "day2.yaml").exists()


def test_the_index_opens_a_day_of_the_run_in_the_screenshot_tool_and_the_viewer(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from tools.screenshot import main as screenshot
    from tools.week_index import INDEX_KIND, main as list_days, write_json

    for day in (1, 2):
        (tmp_path / f"day{day}.rrd").write_bytes(b"rrd")
    index = tmp_path / "index.json"
    write_json(index, {"kind": INDEX_KIND, "entries": [
        {"day": 1, "rrd": "day1.rrd"}, {"day": 2, "rrd": "day2.rrd"}, {"day": 3, "rrd": None, "removed": True}]})
    assert recording_of_day(index, 1) == tmp_path / "day1.rrd" and recording_of_day(index, None) == tmp_path / "day2.rrd"
    assert screenshot([str(index), str(tmp_path / "out.png"), "--day", "3"]) == 1
    assert "day 3 has no recording; days with one: 1, 2" in capsys.readouterr().err
    assert list_days([str(index)]) == 0
    assert capsys.readouterr().out.split() == [str(tmp_path / "day1.rrd"), str(tmp_path / "day2.rrd")]
    (tmp_path / "other.json").write_text("{}")
    assert list_days([str(tmp_path / "other.json")]) == 1 and "not an index of a long run" in capsys.readouterr().err


def test_days_on_the_command_line_repeat_a_single_day_scene_on_the_next_dates(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import dsr.collector

    monkeypatch.setenv("CHRONAV_RUNS", str(tmp_path / "runs"))
    released: list[int] = []
    real_release = dsr.collector.release_free_memory
    monkeypatch.setattr(dsr.collector, "release_free_memory", lambda collect=True: released.append(real_release()) or 0)
    tiny = WEEK.parent / "eval_tiny.yaml"
    result = CliRunner().invoke(app, ["launch", str(tiny), "--in-process", "--days", "3", "--no-record", "--json"])
    assert result.exit_code == 0, result.output
    assert len(released) == 3          # what each day freed went back to the system at its end
    summary = json.loads(result.stdout)
    assert [(d["date"], d["status"], list(d["missions"])) for d in summary["days"]] == [
        ("2026-11-25", "ok", ["cross", "dock"]), ("2026-11-26", "ok", ["cross", "dock"]),
        ("2026-11-27", "ok", ["cross", "dock"])]
    # Bounded by design: each day's graph is the day's world, nothing carried over from the days before.
    assert summary["days"][0]["dsr"] == summary["days"][1]["dsr"] == summary["days"][2]["dsr"]
    refused = CliRunner().invoke(app, ["launch", str(tiny), "--in-process", "--days", "0"])
    assert refused.exit_code == 2 and "--days" in refused.output


def test_an_in_process_run_forgets_tombstones_as_it_goes(tmp_path: Path) -> None:
    """In-process the agents share one graph, the only replica: the run forgets removals every 50
    rounds (tools/inprocess.py), so a day's tombstones do not pile up (center_week's Monday kept
    323 of them, its Tuesday 426)."""
    import time

    from tools.inprocess import _InProcessRun

    ticks: list[dict[str, object]] = []
    run = _InProcessRun(spec=load_scene(WEEK.parent / "eval_tiny.yaml").scene, scene_path=WEEK, run_id="t",
                        run_dir=tmp_path, record=False, started=time.monotonic(), on_tick=ticks.append)
    for day in range(3):                       # a day's churn of people and intentions, three times over
        for i in range(40):
            node = run.graph.insert_node("object", f"churn{day}_{i}")
            run.graph.delete_node(node.id)
        assert run.graph.tombstones() == 40
        run.done(49)
        assert run.graph.tombstones() == 40    # between two rounds of upkeep they are kept
        run.done(50)
        assert run.graph.tombstones() == 0 and ticks[-1]["dsr"] == {"nodes": 0, "edges": 0, "tombstones": 0}


def test_a_day_scene_points_at_the_scene_folders_files() -> None:
    data = {"name": "s", "clock": {"date": dt.date(2026, 11, 30), "days": 3}, "agenda_file": "agenda.ics",
            "map": {"file": "maps/ward.yaml"}}
    day = day_scene_data(data, 3, Path("/centre/scenes"), first=dt.date(2026, 11, 30))
    assert day["agenda_file"] == "/centre/scenes/agenda.ics" and day["map"]["file"] == "/centre/scenes/maps/ward.yaml"
    assert day["clock"] == {"date": dt.date(2026, 12, 2)} and day["name"] == "s-day3"


def test_the_days_of_a_launched_run_share_one_restart_budget(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A crash loop late on day 1 still counts early on day 2: every day's launch gets the same budget."""
    from tools.launch import RunResult
    from tools.week import run_days

    budgets = []

    def fake_launch(scene: Path, *, restart_budget: object, runs_dir: Path, **_: object) -> RunResult:
        budgets.append(restart_budget)
        restart_budget.take("agenda", "exited with 1")          # type: ignore[attr-defined]
        run_dir = runs_dir / Path(scene).stem
        run_dir.mkdir()
        return RunResult(scene="s", run_dir=run_dir, rrd_path=None, missions={}, events=[], restarts={}, wall_s=0.1)

    monkeypatch.setattr("tools.launch.run_system", fake_launch)
    result = run_days(WEEK, runs_dir=tmp_path, restart_limit=3)
    assert len(budgets) == 2 and budgets[0] is budgets[1] and budgets[0].used("agenda") == 2
    summary = json.loads((result.run_dir / "result.json").read_text())
    assert summary["restarts_total"] == 2 and summary["restart_budget"] == "3 per rolling hour"


def test_a_merge_that_fails_half_way_leaves_no_recording_behind(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    """The day's recording is merged into a partial file and renamed: a disk that fills during the
    merge (the viewer's CLI writes half, then fails) leaves neither a truncated .rrd nor the partial."""
    from tools.launch import merge_recordings

    fake = tmp_path / "rerun"
    fake.write_text('#!/bin/sh\nfor last; do :; done\nprintf half > "$last"\necho "No space left on device" >&2\nexit 1\n')
    fake.chmod(0o755)
    monkeypatch.setattr("tools.launch.rerun_binary", lambda: fake)
    part = tmp_path / "rrd" / "sim_robot-1.rrd"
    part.parent.mkdir()
    part.write_bytes(b"part")
    out = tmp_path / "day1.rrd"
    assert merge_recordings([part], out) is None
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rerun", "rrd"]
    assert "No space left on device" in capsys.readouterr().err



def test_a_recorder_rotates_its_part_every_slot_and_each_part_has_the_static_rows(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import rerun as rr

    from agents.runtime.recording import ROTATE_ENV, Recorder, part_slot

    monkeypatch.setenv(ROTATE_ENV, "3600")
    monkeypatch.setenv("RERUN", "on")
    recorder = Recorder("sim_robot", tmp_path, "rid", day=dt.date(2026, 12, 1))
    recorder.line_strip("world/map/walls", [[0, 0], [6, 0]], color=[0, 0, 0], static=True)
    for sim_s in (9 * 3600 + 5.0, 9 * 3600 + 60.0, 10 * 3600 + 1.0):
        recorder.set_time(sim_s)
        recorder.log("world/truth/robot", rr.Points2D([[sim_s / 3600, 0]]))
    recorder.close()
    parts = sorted((tmp_path / "rrd").glob("*.rrd"))
    assert [part_slot(p) for p in parts] == [9, 10]            # the unslotted first part is gone
    for part in parts:
        assert {"world/map/walls", "world/truth/robot"} <= recording_entities(part)
    monkeypatch.setenv(ROTATE_ENV, "5")
    with pytest.raises(ValueError, match="at least 60 sim seconds"):
        Recorder("sim_robot", tmp_path, "rid")


@pytest.mark.parametrize(("times_s", "hourly"), [((9 * 3600 + 5.0, 9 * 3600 + 1800.0), False),
                                                 ((9 * 3600 + 5.0, 10 * 3600 + 1.0), True)])
def test_a_rotated_run_is_one_file_within_an_hour_and_one_per_hour_beyond(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, times_s: tuple[float, ...], hourly: bool) -> None:
    import rerun as rr

    from agents.runtime.recording import ROTATE_ENV, Recorder
    from tools.launch import merge_run_recording

    monkeypatch.setenv(ROTATE_ENV, "3600")
    monkeypatch.setenv("RERUN", "on")
    run_dir = tmp_path / "run-1"
    recorder = Recorder("sim_robot", run_dir, "run-1", day=dt.date(2026, 12, 1))
    recorder.line_strip("world/map/walls", [[0, 0], [6, 0]], color=[0, 0, 0], static=True)
    for sim_s in times_s:
        recorder.set_time(sim_s)
        recorder.log("world/truth/robot", rr.Points2D([[sim_s / 3600, 0]]))
    recorder.close()
    rrd, hours = merge_run_recording(run_dir, "run-1")
    if hourly:
        assert rrd is None and [h["hour"] for h in hours] == ["09:00", "10:00"]
        assert sorted(p.name for p in tmp_path.glob("*.rrd")) == ["run-1-h09.rrd", "run-1-h10.rrd"]
    else:
        assert hours == [] and rrd == tmp_path / "run-1.rrd"
        assert sorted(p.name for p in tmp_path.glob("*.rrd")) == ["run-1.rrd"]
        assert {"world/map/walls", "world/truth/robot"} <= recording_entities(rrd)
    assert not list((run_dir / "rrd").glob("*.rrd"))                  # the parts have served


@pytest.mark.slow
def test_a_real_time_day_is_recorded_hour_by_hour(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CHRONAV_RUNS", str(tmp_path / "runs"))
    monkeypatch.setenv("RERUN", "on")
    monkeypatch.delenv("CHRONAV_RECORDING_ROTATE_S", raising=False)
    result = CliRunner().invoke(app, ["launch", str(WEEK), "--in-process", "--rate", "1", "--days", "1", "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    (entry,) = read_index(Path(summary["index"]))["entries"]
    assert entry["rrd"] is None and [h["hour"] for h in entry["hours"]] == ["09:00", "10:00"]
    run_dir = Path(summary["run_dir"])
    assert sorted(p.name for p in run_dir.glob("*.rrd")) == sorted(h["rrd"] for h in entry["hours"])
    for hour in entry["hours"]:
        assert "world/map/walls" in recording_entities(run_dir / hour["rrd"])      # each hour opens on its own
    assert summary["days"][0]["rrd_bytes"] == sum((run_dir / h["rrd"]).stat().st_size for h in entry["hours"])
    at_1001 = recording_of_day(Path(summary["index"]), 1, 10 * 3600 + 60)
    assert at_1001 == run_dir / entry["hours"][1]["rrd"]
    assert "CHRONAV_RECORDING_ROTATE_S" not in os.environ                 # only for that day's agents


@pytest.mark.slow
def test_a_single_real_time_day_without_days_is_recorded_hour_by_hour(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`chronav launch SCENE --rate 1` of a one-day scene (no --days, not a run of days) rotates
    its recording every hour too, and says so in its result."""
    import yaml

    monkeypatch.setenv("CHRONAV_RUNS", str(tmp_path / "runs"))
    monkeypatch.setenv("RERUN", "on")
    monkeypatch.delenv("CHRONAV_RECORDING_ROTATE_S", raising=False)
    data = yaml.safe_load(WEEK.read_text())
    data["clock"].pop("days")                                                  # Monday only
    data["agenda_changes"] = [c for c in data.get("agenda_changes", []) if c.get("day", 1) == 1]
    scene = tmp_path / "monday.yaml"
    scene.write_text(yaml.safe_dump(data))
    result = CliRunner().invoke(app, ["launch", str(scene), "--in-process", "--rate", "1", "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["rrd"] is None and [h["hour"] for h in summary["hours"]] == ["09:00", "10:00"]
    run_dir = Path(summary["run_dir"])
    for hour in summary["hours"]:
        assert "world/map/walls" in recording_entities(Path(hour["rrd"]))          # each hour opens on its own
    assert not list((run_dir / "rrd").glob("*.rrd"))                           # the parts have served
    written = json.loads((run_dir / "result.json").read_text())
    assert [h["rrd"] for h in written["hours"]] == [h["rrd"] for h in summary["hours"]]
    assert "CHRONAV_RECORDING_ROTATE_S" not in os.environ


def test_real_time_is_a_rate_of_one_or_less_or_a_ros_robot() -> None:
    from tools.launch import realtime_run

    assert realtime_run(None, 1.0) and realtime_run(0.5, 60.0) and realtime_run(None, 60.0, robot="ros")
    assert not realtime_run(None, 60.0) and not realtime_run(2.0, 1.0)


@pytest.mark.parametrize(("rate", "rotates"), [(1.0, True), (60.0, False)])
def test_a_launched_real_time_run_starts_its_agents_recording_hour_by_hour(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, rate: float, rotates: bool) -> None:
    """`chronav launch SCENE --rate 1` (one day, processes): the agents' environment carries the
    rotation.  It was set after the environment had been made, so the agents of such a run wrote
    one part each all day, and flushed their recording as often as a fast run."""
    from agents.runtime.recording import ROTATE_ENV
    from tools.launch import _prepare_run

    monkeypatch.delenv(ROTATE_ENV, raising=False)
    run = _prepare_run(WEEK, rate=rate, runs_dir=tmp_path, record=True, restart_limit=3, agent_options=None,
                       ros_domain=None, robot="sim")
    for name in run.agents:
        assert (ROTATE_ENV in run.supervisor.processes[name].env) is rotates, name
    assert ROTATE_ENV not in os.environ


def test_a_later_day_that_cannot_start_is_an_error_of_that_day_and_the_run_goes_on(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from tools.launch import LaunchError, RunResult
    from tools.week import run_days

    calls = []

    def flaky_launch(scene: Path, *, runs_dir: Path, **_: object) -> RunResult:
        calls.append(Path(scene).name)
        if len(calls) == 2:
            raise LaunchError("the Zenoh router did not listen on tcp/127.0.0.1:1234")
        run_dir = runs_dir / Path(scene).stem
        run_dir.mkdir()
        return RunResult(scene="s", run_dir=run_dir, rrd_path=None, missions={"m": {"state": "done"}}, events=[],
                         restarts={}, wall_s=0.1)

    monkeypatch.setattr("tools.launch.run_system", flaky_launch)
    scene = _variant(tmp_path, days=3)
    result = run_days(scene, runs_dir=tmp_path / "runs")
    assert calls == ["day1.yaml", "day2.yaml", "day3.yaml"]
    assert [(d["status"], d.get("reason")) for d in result.days] == [
        ("ok", None), ("error", "the Zenoh router did not listen on tcp/127.0.0.1:1234"), ("ok", None)]
    assert not result.ok and result.outcome == "failed"


def test_scene_day_writes_one_day_of_a_scene_for_the_offline_commands(tmp_path: Path) -> None:
    out = tmp_path / "tuesday.yaml"
    result = CliRunner().invoke(app, ["scene", "day", str(WEEK), "2", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "2026-12-01 (1 activities, 2 missions)" in result.output
    world = load_world(out)
    assert [m.id for m in world.scene.missions] == ["back", "dock"] and [a.id for a in world.agenda.activities] == ["music"]
    missing = CliRunner().invoke(app, ["scene", "day", str(tmp_path / "nope.yaml"), "2", "--out", str(out)])
    assert missing.exit_code == 1 and "no such scene file" in missing.output


def test_bench_week_summarizes_growth_from_the_day_records() -> None:
    from tools.bench.bench_week import summarize

    def day(number: int, rss: float, nodes: int, tombstones: int, status: str = "ok") -> dict[str, object]:
        return {"day": number, "status": status, "wall_s": 30.0, "rrd_bytes": 3 * 1024 * 1024,
                "bytes_written": 6 * 1024 * 1024, "agents": {"in_process": {"rss_mb": rss, "cpu_s": 1.0}},
                "dsr": {"nodes": nodes, "edges": 10, "tombstones": tombstones},
                "missions_summary": {"total": 2, "done": 2}}

    report = summarize([day(1, 400.0, 60, 0), {"day": 2, "status": "refused"}, day(3, 440.0, 66, 3)], 90.0, 3)
    assert report["rss_growth_day3_over_day1"] == 1.1 and report["dsr_growth_day3_over_day1"] == 3.0
    assert report["week_wall_min"] is None and report["week_wall_min_projected"] == 3.5
    assert (report["days_ok"], report["missions"], report["rrd_mb_per_day"]) == (2, 4, 3.0)


def test_a_launched_days_last_status_waits_for_its_tombstones_to_be_forgotten(monkeypatch: pytest.MonkeyPatch) -> None:
    """The day's DSR counts are read once the last removals are forgotten (a few digest rounds),
    not while they are in flight, and never later than ``settle_s``."""
    import tools.launch as launch

    class Graph:
        def __init__(self, forgotten_after: int | None) -> None:
            self.dispatches, self.forgotten_after = 0, forgotten_after

        def tombstones(self) -> int:
            return 0 if self.forgotten_after is not None and self.dispatches >= self.forgotten_after else 4

        def dispatch(self, timeout: float) -> None:
            self.dispatches += 1

    monkeypatch.setattr(launch, "_status", lambda graph, supervisor, started: {"dsr": {"tombstones": graph.tombstones()}})
    run = SimpleNamespace(started=0.0, run_dir=Path("r"), endpoint="tcp/127.0.0.1:1", graph_name="g")
    settling = Graph(forgotten_after=3)
    assert launch._settled_status(settling, None, run, settle_s=5.0)["dsr"] == {"tombstones": 0}
    assert settling.dispatches == 3
    never = Graph(forgotten_after=None)
    assert launch._settled_status(never, None, run, settle_s=0.3)["dsr"] == {"tombstones": 4}   # bounded wait
    assert launch._settled_status(Graph(forgotten_after=0), None, run, settle_s=5.0)["run"]["graph"] == "g"


def test_a_bad_log_rotation_setting_is_refused_before_any_process_starts(tmp_path: Path) -> None:
    """CHRONAV_LOG_ROTATE_S is read by every process of a launched run (dsr/log_rotation.py): a bad
    one is refused once, by the command, with its name and what to give, and no run is made."""
    runs = tmp_path / "runs"
    result = CliRunner().invoke(app, ["launch", str(WEEK), "--rate", "1", "--days", "1", "--timeout", "5"],
                                env={"CHRONAV_LOG_ROTATE_S": "7", "CHRONAV_RUNS": str(runs), "COLUMNS": "300"})
    assert result.exit_code == 2, result.output
    assert "CHRONAV_LOG_ROTATE_S='7'" in result.output and "divisor of a day" in result.output
    assert not runs.exists()

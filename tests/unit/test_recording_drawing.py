"""The recording's drawing layer (issue 33), single process: written with the real Recorder to a
file, read back with Rerun's own API.

- the decision layer logs a social map's zones with its stamp at the map's time, holds no
  people in its raster, and is cleared when the navigation uses no map;
- labels: short ids, decluttered in a crowd; the DSR view keeps what a reader needs;
- the clock timeline is the scene's date plus sim time; events start with clock and agent;
- the screenshot tour finds each mission's start, closest approach and arrival in a recording.
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from rerun.chunk import RrdReader

from agents.runtime.drawing.dsr_graph import GraphLogger, label, layout
from agents.runtime.drawing.labels import declutter, short_ids
from agents.runtime.drawing.social_map import WALL, DecisionLogger, DecisionStamp, class_image, zone_rings
from agents.runtime.recording import Recorder, event_text
from agents.world.offline import SceneMaps, graph_at
from agents.world.scene_world import load_world
from tests.support import REPO_ROOT
from tools.screenshot import end_of, parse_size, tour_stops

TINY = REPO_ROOT / "tests" / "data" / "eval_tiny.yaml"
DAY = dt.date(2026, 11, 25)


@pytest.fixture
def recorder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Recorder:
    monkeypatch.setenv("RERUN", "on")
    return Recorder("social_navigation", tmp_path, "test-run", day=DAY)


def _store(rec: Recorder):
    assert rec.path is not None
    path = rec.path
    rec.close()
    return RrdReader(str(path)).stream().collect()


def test_short_ids_and_declutter() -> None:
    assert short_ids(["nurse_rosa", "res_ana", "robot", "visitor_ana"]) == ["rosa", "res_ana", "robot", "visitor_ana"]
    labels = declutter(["a", "b", "c"], [(0.0, 0.0), (0.5, 0.0), (3.0, 0.0)], min_gap_m=1.0)
    assert labels == ["a", "", "c"], "the second label is within a metre of the first: hidden"


def test_decision_layer_logs_zones_with_their_stamp_and_clears(recorder: Recorder) -> None:
    smap = SceneMaps.load(TINY).at(36000.0)            # 10:00, the game runs, one resident
    classes = class_image(smap)
    assert set(np.unique(classes)) <= {0, 3, 4, 5, 6, 7, 8}, "no people in the raster: their zones are vectors"
    assert np.any(classes == WALL)
    rings = zone_rings(smap)
    assert rings["intimate"] and rings["personal"] and rings["social"]
    decision = DecisionLogger(recorder)
    recorder.set_time(smap.t_s)
    decision.log_map(smap, DecisionStamp(map_s=smap.t_s, planned_s=smap.t_s - 0.4, seen_s=smap.t_s - 3.0))
    recorder.set_time(smap.t_s + 5.0)
    decision.clear()
    store = _store(recorder)
    table = store.reader(index="sim_time", contents="/world/decision/**").to_arrow_table()
    zone = table.column("/world/decision/zones/intimate:LineStrips2D:strips").to_pylist()
    stamp = table.column("/world/decision/zones/intimate:map_s").to_pylist()
    assert zone[0] and stamp[0] == [smap.t_s]
    resident = smap.people[0]
    assert any(min(np.hypot(*(np.asarray(r) - [resident.x, resident.y]).T)) < 0.6 for r in zone[0])
    texts = table.column("/world/decision/stamp:TextLog:text").to_pylist()
    assert texts[0] == ["map 10:00:00 | path 09:59:59 | people seen 09:59:57 - STALE 3.0 s"]
    assert texts[1] == ["no navigation task"]
    rows = store.reader(index="log_time", contents="/world/decision/zones/intimate").to_arrow_table()
    last = rows.column("/world/decision/zones/intimate:LineStrips2D:strips").to_pylist()[-1]
    assert not last, "after clear() the zones entity holds nothing"


def test_clock_timeline_and_event_text(recorder: Recorder) -> None:
    recorder.set_time(34247.25)
    recorder.event("09:30:47 stalled")
    recorder.event("door d opened")
    store = _store(recorder)
    table = store.reader(index="log_time", contents="/events/**").to_arrow_table()
    clock = pd.Timestamp(table.column("clock")[0].as_py())
    naive = clock.tz_localize(None) if clock.tz else clock
    assert naive == pd.Timestamp("2026-11-25 09:30:47.250"), "the clock is the scene's date + sim time"
    assert [t[0] for t in table.column("/events/social_navigation:TextLog:text").to_pylist()] == [
        "09:30:47 social_navigation: stalled", "social_navigation: door d opened"]
    assert event_text("executive", "10:45 mission m done") == "10:45:00 executive: mission m done"


def test_dsr_view_keeps_rooms_objects_people_and_folds_the_rest(tmp_path: Path,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("RERUN", "on")
    world = load_world("center_day")
    graph = graph_at(world, 9 * 3600.0 + 1800.0)
    rec = Recorder("launcher", tmp_path, "test-run", day=DAY)
    GraphLogger(rec).maybe_log(graph, 34200.0)
    store = _store(rec)
    table = store.reader(index="sim_time", contents="/dsr").to_arrow_table()
    labels = table.column("/dsr:GraphNodes:labels").to_pylist()[0]
    positions = np.asarray(table.column("/dsr:GraphNodes:positions").to_pylist()[0])
    kinds = {n.type for n in graph.nodes()}
    assert {"clock", "world"} <= kinds and not {"world", "clock"} & set(labels)
    assert "rosa" in labels and "lounge" in labels and "tv" in labels
    assert len(set(map(tuple, positions.round(3)))) == len(positions), "no two nodes on one spot"
    assert label("activity", "activity/tv_game", "running") == "tv_game [running]"
    assert len(layout(graph, [n.id for n in graph.nodes() if n.type == "room"])) == 5


def test_tour_finds_start_closest_approach_and_arrival(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("RERUN", "on")
    from agents.runtime.drawing.bodies import log_robot, log_true_people

    sim = Recorder("sim_robot", tmp_path, "tour", day=DAY)
    executive = Recorder("executive", tmp_path, "tour", day=DAY)
    executive.set_time(36000.0)
    executive.event("10:00 mission m1 (pose:5,0,0) started")
    for k in range(11):
        t = 36000.0 + k
        sim.set_time(t)
        log_robot(sim, "robot", 0.3, (float(k) * 0.5, 0.0, 0.0), 0.5, np.empty((0, 2)), [])
        log_true_people(sim, ["ann"], [(3.0, 1.0)])
    executive.set_time(36010.0)
    executive.event("10:00:10 mission m1 done (10 s)")
    paths = [sim.path, executive.path]
    sim.close()
    executive.close()
    merged = tmp_path / "merged.rrd"
    from tools.launch import merge_recordings

    merge_recordings(sorted(paths), merged)
    # Issue 39: once merged, the per-agent parts (39 MB for center_day) are gone, and their folder.
    assert not any(p.exists() for p in paths) and not paths[0].parent.exists()
    store = RrdReader(str(merged)).stream().collect()
    stops = [(s.mission, s.what, s.sim_s) for s in tour_stops(store)]
    assert stops == [("m1", "start", 36000.0), ("m1", "closest-1.00m", 36006.0), ("m1", "arrival", 36010.0)]
    assert end_of(store) == 36010.0
    assert parse_size("1280x720") == (1280, 720)


def test_a_failed_merge_keeps_the_per_agent_recordings(tmp_path: Path) -> None:
    from tools.launch import merge_recordings

    part = tmp_path / "rrd" / "sim_robot-1.rrd"
    part.parent.mkdir()
    part.write_bytes(b"not a recording")
    assert merge_recordings([part], tmp_path / "merged.rrd") is None
    assert part.read_bytes() == b"not a recording"

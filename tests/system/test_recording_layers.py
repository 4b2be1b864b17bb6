"""Issue 33 (multi-process): the recording shows, at every instant, what was true then.

A short `chronav launch` of a small centre where eight people walk (tests/data/crowd_small.yaml
with one mission across it), its merged recording read back with Rerun's own dataframe API:

- the decision layer: the zones the navigation used are logged at every social-map update (every
  path it adopted has its map logged at the same instant, and while it drives there is no gap
  longer than a few replan periods), each with its stamp (``map_s``) equal to the instant shown;
  after arrival the layer is cleared (nothing kept from an old plan);
- no person's zone is drawn where no person was: every intimate zone the navigation used holds a
  person of the world layer (the simulator's true positions at that instant);
- the time columns carry the scene clock: ``clock`` is the scene's date plus ``sim_time``, and
  every event's text starts with its clock time.
"""

from __future__ import annotations

import datetime as dt
import re
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
import shapely
import yaml

from tests.system.launch_helpers import launch_json
from tests.system.recording import load_store

pytestmark = pytest.mark.slow
ROOT = Path(__file__).resolve().parents[2]
DATE = dt.date(2026, 11, 25)
ZONES = "/world/decision/zones/intimate"
MIN_ZONE_M2 = 0.05       # a person's intimate zone is ~0.3 m^2 or more; smaller rings are contour slivers
REPLAN_GAP_S = 1.0       # the map is rebuilt every 0.2 s of sim time while the robot drives (lockstep)
PERSON_SLACK_M = 0.5     # tracker noise and lag, a walker's zone stretched ahead: this close to a true person is true


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    directory = tmp_path_factory.mktemp("recording_layers")
    data = yaml.safe_load((ROOT / "tests" / "data" / "crowd_small.yaml").read_text())
    data["name"] = "crowd_small_mission"
    data["clock"] = {**data["clock"], "date": DATE.isoformat(), "start": "09:00", "end": "09:04"}
    data["missions"] = [{"id": "across", "time": "09:01", "goal": {"pose": [15.0, 5.0, 1.5708]},
                         "description": "along the corridor among walking people, into the lounge"}]
    scene = directory / "crowd_small_mission.yaml"
    scene.write_text(yaml.safe_dump(data, sort_keys=False))
    result = launch_json(str(scene), directory / "launch.log", timeout_s=240)
    assert result["returncode"] == 0 and result["missions"]["across"]["state"] == "done", result
    result["store"] = load_store(Path(result["rrd"]))
    return result


def _rows(store: Any, entity: str, *fields: str) -> list[dict[str, Any]]:
    """Every row of ``entity`` (indexed by log time: rows logged at one sim time stay apart)."""
    table = store.reader(index="log_time", contents=entity).to_arrow_table()
    names = ["sim_time", "clock", *(f"{entity}:{f}" for f in fields)]
    columns = {n: table.column(n).to_pylist() if n in table.column_names else [None] * table.num_rows
               for n in names}
    rows = [{n: columns[n][i] for n in names} for i in range(table.num_rows)]
    rows = [r for r in rows if r["sim_time"] is not None]
    return sorted(rows, key=lambda r: r["sim_time"])


def _seconds(value: Any) -> float:
    return value.total_seconds()


def test_zones_are_logged_at_every_social_map_update_with_their_stamp(run: dict[str, Any]) -> None:
    store = run["store"]
    zones = _rows(store, ZONES, "map_s", "LineStrips2D:strips")
    logged = [r for r in zones if r[f"{ZONES}:map_s"]]
    assert len(logged) > 20, "the navigation drove for seconds: it rebuilt its map many times"
    for row in logged:   # the stamp is the instant the map was computed, and it is shown at that instant
        assert row[f"{ZONES}:map_s"][0] == pytest.approx(_seconds(row["sim_time"]), abs=1e-6)
    map_times = np.array([_seconds(r["sim_time"]) for r in logged])
    events = _rows(store, "/events/social_navigation", "TextLog:text")
    paths = [_seconds(r["sim_time"]) for r in events if r["/events/social_navigation:TextLog:text"]
             and " path " in r["/events/social_navigation:TextLog:text"][0]]
    assert paths, "the navigation adopted a path"
    for t in paths:   # every path adopted was planned on a map logged at that instant
        assert np.min(np.abs(map_times - t)) < 1e-6, f"no social map logged with the path adopted at {t:.2f}"
    arrived = [_seconds(r["sim_time"]) for r in events if r["/events/social_navigation:TextLog:text"]
               and "reached goal" in r["/events/social_navigation:TextLog:text"][0]]
    assert arrived, "the mission arrived"
    driving = map_times[(map_times >= paths[0]) & (map_times <= arrived[0])]
    assert len(driving) > 10
    # From the first replan on (before it the simulator's clock still flows while the robot waits
    # for its first command), the map is rebuilt, and logged, every replan period.
    gaps = np.diff(driving[1:])
    assert gaps.max() <= REPLAN_GAP_S, f"the zones shown were {gaps.max():.1f} s old at some instant"
    # After arrival the navigation uses no map: the layer is cleared, not left showing old zones.
    after = [r for r in zones if _seconds(r["sim_time"]) >= arrived[0]]
    assert after and not after[-1][f"{ZONES}:LineStrips2D:strips"], "old zones stay on screen after arrival"


def test_no_zone_is_drawn_where_no_person_was(run: dict[str, Any]) -> None:
    store = run["store"]
    truth = _rows(store, "/world/truth/people", "Points2D:positions")
    truth_times = np.array([_seconds(r["sim_time"]) for r in truth])
    checked = 0
    for row in _rows(store, ZONES, "LineStrips2D:strips"):
        strips = row[f"{ZONES}:LineStrips2D:strips"]
        if not strips:
            continue
        t = _seconds(row["sim_time"])
        k = int(np.searchsorted(truth_times, t, side="right")) - 1
        assert k >= 0, f"a zone at {t:.2f} before the world layer holds anyone"
        people = [shapely.Point(p) for p in truth[k]["/world/truth/people:Points2D:positions"]]
        for ring in strips:
            zone = shapely.Polygon(ring) if len(ring) >= 4 else None
            if zone is None or zone.area < MIN_ZONE_M2:
                continue
            nearest = min(zone.distance(p) for p in people)
            assert nearest <= PERSON_SLACK_M, (f"an intimate zone at {t:.2f} s around {zone.centroid} is "
                                               f"{nearest:.2f} m from every person")
            checked += 1
    assert checked > 20


def test_time_columns_carry_the_scene_clock(run: dict[str, Any]) -> None:
    store = run["store"]
    midnight_ns = int(dt.datetime(DATE.year, DATE.month, DATE.day, tzinfo=dt.UTC).timestamp()) * 10**9
    for entity, field in ((ZONES, "map_s"), ("/world/truth/robot/body", "Points2D:positions")):
        rows = _rows(store, entity, field)
        assert rows
        for row in rows:
            clock_ns, sim_ns = pd.Timestamp(row["clock"]).value, pd.Timedelta(row["sim_time"]).value
            assert abs(clock_ns - midnight_ns - sim_ns) < 1000, f"{entity}: clock is not the scene's date + sim_time"
            assert 9 * 3600 <= sim_ns / 1e9 <= 9 * 3600 + 241, "outside the scene's day"
    for agent in ("executive", "social_navigation", "sim_robot"):
        texts = [r[f"/events/{agent}:TextLog:text"][0] for r in _rows(store, f"/events/{agent}", "TextLog:text")
                 if r[f"/events/{agent}:TextLog:text"]]
        assert texts, agent
        for text in texts:
            found = re.match(rf"(\d\d:\d\d:\d\d) {agent}: ", text)
            assert found is not None, f"event without its clock time: {text!r}"
            assert "09:00" <= found.group(1) <= "09:04:01", text

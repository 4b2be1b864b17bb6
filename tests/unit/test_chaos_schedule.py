"""The pure parts of `chronav chaos` (tools/chaos/command.py), offline: random schedules are
reproducible and reach every mission, a schedule file round-trips and a bad fault is named, and the
lost-write check finds each kind of loss.  On the schedule the fault run of
tests/system/test_faults.py injects (tests/data/chaos_kills.json) and on icra_usecase, its scene.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from agents.world.scene_world import load_world
from dsr import DSRGraph
from tests.support import REPO_ROOT
from tools.chaos.command import ChaosError, Fault, load_schedule, lost_writes, random_schedule

KILLS: list[dict[str, Any]] = json.loads((REPO_ROOT / "tests" / "data" / "chaos_kills.json").read_text())
EXTRA = next(fault["change"] for fault in KILLS if fault["action"] == "agenda")
MISSIONS = ("m0930", "m1045", "m1115", "m1315")


def test_random_schedules_are_reproducible_and_hit_every_mission() -> None:
    loaded = load_world("icra_usecase")
    first = random_schedule(loaded, seed=3, faults=12, duration_s=3)
    assert first == random_schedule(loaded, seed=3, faults=12, duration_s=3)
    assert first != random_schedule(loaded, seed=4, faults=12, duration_s=3)
    assert [f.mission for f in first] == [m for m in MISSIONS for _ in range(3)]  # in mission order
    for mission in MISSIONS:
        times = [f.at_s for f in first if f.mission == mission]
        assert times == sorted(times) and all(0 <= t <= 3 for t in times)
    assert {f.action for f in first} == {"kill", "stop", "agenda"}
    for fault in first:
        if fault.action == "agenda":
            assert json.loads(fault.change or "")["op"] in ("add", "move", "cancel")
        if fault.action == "stop":
            assert 0.3 <= fault.hold_s <= 3.0


def test_schedule_files_round_trip_and_name_bad_faults(tmp_path: Path) -> None:
    good = tmp_path / "good.json"
    good.write_text(json.dumps(KILLS))
    faults = load_schedule(good)
    assert [f.target for f in faults] == [k["target"] for k in KILLS]
    assert json.loads(faults[2].change or "") == EXTRA
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps([KILLS[0], {"action": "kill", "target": "kernel"}]))
    with pytest.raises(ChaosError, match=r"bad.json: fault 1: .*kernel"):
        load_schedule(bad)
    bad.write_text('[{"action": "kill", "target": "router", "at": 3}]')
    with pytest.raises(ChaosError, match="fault 0"):
        load_schedule(bad)
    with pytest.raises(ChaosError, match="needs a change"):
        Fault("agenda", "agenda")


def _final_graph(loaded: Any, changes: list[str]) -> DSRGraph:
    """What a healthy run leaves: missions done, the agenda log replayed into activity nodes."""
    from agents.lib.agenda.changes import apply_change, parse_change

    graph = DSRGraph("test", graph="faults")
    day = loaded.agenda
    for text in changes:
        day = apply_change(day, parse_change(text), known_objects={o.name for o in loaded.scene.objects})
    graph.insert_node("agenda", "agenda", {"changes": changes, "applied": []})
    for activity in day.activities:
        graph.insert_node("activity", f"activity/{activity.id}", {
            "activity_id": activity.id, "object": activity.object, "start_s": activity.start_s,
            "end_s": activity.end_s, "state": "cancelled" if activity.cancelled else "scheduled"})
    for mission in MISSIONS:
        graph.insert_node("mission", f"mission/{mission}", {"mission_id": mission, "state": "done"})
    return graph


def test_lost_writes_finds_each_kind_of_loss() -> None:
    loaded = load_world("icra_usecase")
    change = json.dumps(EXTRA)
    graph = _final_graph(loaded, [change])
    assert lost_writes(graph, loaded, set(MISSIONS), [change]) == []
    graph.update_node(graph.get_node_by_name("mission/m1045").id, {"state": "active"})
    graph.update_node(graph.get_node_by_name("activity/serious_game").id, {"start_s": 0.0})
    graph.delete_node(graph.get_node_by_name("activity/faults_extra").id)
    cancel = json.dumps({"op": "cancel", "id": "table_therapy"})
    lost = lost_writes(graph, loaded, set(MISSIONS), [change, cancel])
    assert any("m1045 was done" in line for line in lost)
    assert any("serious_game" in line and "differs" in line for line in lost)
    assert any("faults_extra is missing" in line for line in lost)
    assert any("table_therapy" in line and "0 times" in line for line in lost)
    twice = _final_graph(loaded, [change])
    twice.update_node(twice.get_node_by_name("agenda").id, {"changes": [change, change]})
    assert any("2 times" in line for line in lost_writes(twice, loaded, set(), [change]))

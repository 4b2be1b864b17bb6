"""The simulated clock never skips a scheduled event (issue 27).

center_day from 13:00 with one mission at 14:00: the robot is idle, so the simulator skips the
clock toward 14:00 (``skip_idle``).  On the way lie the scene's scripted 13:30 agenda change (the
music session moved) and a door closed at 13:12.  Before, the skip jumped 15 minutes at a time and
the change fired at the end of the piece (13:40:17 on a real run).  Now each is a boundary of the
skip: the agenda agent applies the change with the clock at 13:30 (within one control tick), the
door is shut from 13:12 on, and every crowd routine event is a boundary too.  The agents run in one
process on one in-memory DSR, stepped in turn as their loops would be.
"""

from __future__ import annotations

from pathlib import Path

from agents.sim_robot.agent import CONTROL_DT_S
from agents.world.vocabulary import AGENDA, CLOCK
from scenes.clock import parse_clock
from scenes.loader import SCENES_DIR
from tools.offline_agents import OfflineAgents


def afternoon(tmp_path: Path) -> Path:
    text = (SCENES_DIR / "center_day.yaml").read_text()
    text = text.replace('start: "09:00"', 'start: "13:00"', 1)
    head = text[:text.index("\nmissions:")]
    path = tmp_path / "afternoon.yaml"
    path.write_text(head + '\ndoor_changes:\n  - {at: "13:12", door: door_lounge, open: false}\n'
                    '\nmissions:\n  - {id: m_late, time: "14:00", goal: {room: lounge}}\n')
    return path


def test_a_change_inside_an_idle_stretch_fires_within_one_tick(tmp_path: Path) -> None:
    scene = afternoon(tmp_path)
    centre = OfflineAgents(scene, tmp_path, agents=("sim_robot", "agenda", "executive"))
    graph, sim = centre.graph, centre.sim
    change = next(c for c in sim.world.scripted if c.at_s == parse_clock("13:30"))
    door_at = parse_clock("13:12")
    applied_at = None
    clocks = []
    for _ in range(400):
        centre.tick()
        now = float(graph.get_node_by_name(CLOCK).attrs["now_s"])
        clocks.append(now)
        door = graph.get_node_by_name("door_lounge")
        if now >= door_at + CONTROL_DT_S:
            assert door.attrs.get("open") is False, f"door still open at {now - door_at:.1f} s past 13:12"
        if applied_at is None and change.key in graph.get_node_by_name(AGENDA).attrs.get("applied", []):
            applied_at = now
        if now >= parse_clock("13:40"):
            break
    assert max(clocks) >= parse_clock("13:40"), "the clock skipped on past the change"
    assert any(b - a > 60 for a, b in zip(clocks, clocks[1:])), "the idle stretch was skipped, not walked"
    assert applied_at is not None and change.at_s <= applied_at <= change.at_s + CONTROL_DT_S, \
        f"the 13:30 change fired {applied_at - change.at_s:.1f} s late"
    assert door_at in clocks, "the skip stopped at the door event"

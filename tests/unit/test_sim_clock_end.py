"""The simulated clock stops at the scene's end, however late the simulator's loop runs.

Found on a loaded machine: an idle clock that does not skip moves up to ``IDLE_STEP_MAX_S`` (5 s)
per loop, as much as the wall clock owes it, so a late loop carried the clock past the day's end
(an event stamped 09:04:01 in a scene ending at 09:04). The end is now the idle clock's last event.
"""

from __future__ import annotations

from pathlib import Path

from agents.world.vocabulary import CLOCK
from scenes.clock import parse_clock
from scenes.loader import SCENES_DIR
from tools.offline_agents import OfflineAgents


def test_a_late_loop_does_not_carry_the_clock_past_the_end(tmp_path: Path) -> None:
    text = (SCENES_DIR / "center_day.yaml").read_text()
    text = text.replace('start: "09:00"', 'start: "17:55"', 1)
    head = text[:text.index("\nmissions:")]
    scene = tmp_path / "short.yaml"
    scene.write_text(head + "\nmissions: []\n")
    centre = OfflineAgents(scene, tmp_path, agents=("sim_robot", "agenda", "executive"))
    sim, graph = centre.sim, centre.graph
    sim.clock.skip_idle = False                   # the idle clock walks at its rate, owed by the wall clock
    wall = [0.0]

    def late_wall_clock() -> float:              # every loop comes 7 s of wall time late
        wall[0] += 7.0
        return wall[0]

    sim.wall_clock = late_wall_clock              # type: ignore[method-assign]
    end_s = sim.scene.clock.end_s
    clocks = []
    for _ in range(5000):
        centre.tick()
        clocks.append(float(graph.get_node_by_name(CLOCK).attrs["now_s"]))
        if graph.get_node_by_name(CLOCK).attrs.get("finished"):
            break
    assert graph.get_node_by_name(CLOCK).attrs.get("finished"), "the day did not end"
    assert max(clocks) == end_s, f"the clock reached {max(clocks) - end_s:+.2f} s past the end"
    assert parse_clock("17:55") < end_s

"""The simulator's `busy_rate=0` (what `chronav evaluate` passes): sim time waits while the agents
plan and while a due mission is being started, instead of running on with the wall clock."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from agents.runtime.config import AgentConfig
from agents.runtime.recording import Recorder
from agents.sim_robot.agent import SimRobotAgent
from dsr import DSRGraph
from scenes.loader import SCENES_DIR

SCENE = SCENES_DIR / "icra_usecase.yaml"


def _sim(tmp_path: Path, **options: str) -> tuple[DSRGraph, SimRobotAgent]:
    tmp_path.mkdir(parents=True)
    graph = DSRGraph(agent="test")
    sim = SimRobotAgent(AgentConfig(name="sim_robot", scene=SCENE, run_dir=tmp_path, options=options))
    sim.setup(graph, Recorder("sim_robot", None, None))
    return graph, sim


def _run(sim: SimRobotAgent, wall_s: float) -> float:
    before = sim.now_s
    deadline = time.monotonic() + wall_s
    while time.monotonic() < deadline:
        sim.step()
        time.sleep(0.01)
    return sim.now_s - before


@pytest.mark.parametrize("situation", ["planning", "mission due"])
def test_busy_rate_zero_holds_the_clock(tmp_path: Path, situation: str) -> None:
    runs = {}
    for rate in ("0", "1"):
        graph, sim = _sim(tmp_path / f"{situation}-{rate}", busy_rate=rate)
        if situation == "planning":   # an intention is active but nothing drives yet
            graph.insert_node(type="intention", name="intention/m/0", attrs={"state": "active", "kind": "navigate"})
        else:                         # the mission's time has come; the executive has not started it
            graph.insert_node(type="mission", name="mission/m", attrs={"state": "pending", "time_s": sim.now_s})
        runs[rate] = _run(sim, 0.4)
    assert runs["0"] == 0.0
    assert runs["1"] > 0.1


def test_a_due_mission_behind_a_running_one_does_not_hold_the_clock(tmp_path: Path) -> None:
    """Missions run one at a time: a due one waits for the running one (here a wait for an activity,
    which needs the clock to reach the activity's start).  Holding the clock for it deadlocked an
    in-process day without idle skips (busy_rate=0): nothing changed for 38,000 rounds."""
    graph, sim = _sim(tmp_path / "behind", busy_rate="0", rate="10")
    sim.clock.skip_idle = False
    graph.insert_node(type="mission", name="mission/waiting", attrs={"state": "active", "time_s": sim.now_s})
    graph.insert_node(type="intention", name="intention/waiting/0",
                      attrs={"state": "active", "kind": "wait", "until_s": sim.now_s + 600.0})
    graph.insert_node(type="mission", name="mission/next", attrs={"state": "pending", "time_s": sim.now_s})
    assert _run(sim, 0.4) > 0.1


def test_a_mission_is_due_only_when_its_time_has_come_and_none_runs() -> None:
    """One definition for the clock's mode and its idle step (`mission_due`)."""
    from agents.sim_robot.agent import mission_due
    from agents.world.vocabulary import MissionState, MissionView

    def view(k: int, time_s: float, state: str) -> MissionView:
        return MissionView(k, f"m{k}", "goal", time_s, state, 0)

    pending_now, later = view(1, 100.0, MissionState.PENDING), view(2, 500.0, MissionState.PENDING)
    assert mission_due([pending_now, later], 100.0)
    assert not mission_due([pending_now, later], 99.0)
    assert not mission_due([pending_now, view(3, 10.0, MissionState.ACTIVE)], 200.0)   # one at a time
    assert mission_due([pending_now, view(3, 10.0, MissionState.DONE)], 200.0)
    assert not mission_due([], 200.0)

"""In-process runs: the lockstep scheduler, `chronav launch --in-process`, the perception lockstep.

Why here: the scheduler's promises (one fixed order, a virtual wall clock, a stall reported instead
of spun on, an agent's exception named) are cheap to check with stand-in agents; one in-process run
of the tiny scene through the CLI shows the outputs a launch leaves (tests/system/test_parity.py
compares them with a launch's).
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
from typer.testing import CliRunner

from agents.runtime.config import AgentConfig
from agents.runtime.lockstep import AgentError, Lockstep
from agents.runtime.recording import Recorder
from agents.sim_robot.agent import SimRobotAgent
from agents.world.freshness import LOCKSTEP, mark_observed
from dsr import DSRGraph
from tests.support import REPO_ROOT
from tools.cli import app
from tools.evaluate.pool import WorkerMismatch, check_worker, sweep_fingerprint
from tools.inprocess import merged_options

TINY = REPO_ROOT / "tests" / "data" / "eval_tiny.yaml"


class Counter:
    """A stand-in agent: writes its name and the virtual wall time it saw into the shared log."""

    def __init__(self, name: str, log: list[tuple[str, float]], fail_at: int | None = None, writes: bool = True):
        self.config = SimpleNamespace(name=name)
        self.log, self.fail_at, self.writes = log, fail_at, writes
        self.graph: Any = None
        self.torn_down = False

    def setup(self, graph: Any, recorder: Recorder) -> None:
        self.graph = graph

    def step(self) -> None:
        self.log.append((self.config.name, self.wall_clock()))   # type: ignore[attr-defined]
        if self.fail_at is not None and len(self.log) >= self.fail_at:
            raise ValueError("broken on purpose")
        if self.writes:
            self.graph.insert_node(type="sensor", name=f"{self.config.name}/{len(self.log)}", attrs={})

    def teardown(self) -> None:
        self.torn_down = True


def _scheduler(*agents: Counter) -> Lockstep:
    graph = DSRGraph(agent="test")
    return Lockstep(graph, list(agents), [Recorder(a.config.name, None, None) for a in agents])  # type: ignore[arg-type]


def test_a_round_steps_every_agent_once_in_order_on_a_virtual_clock() -> None:
    log: list[tuple[str, float]] = []
    scheduler = _scheduler(Counter("sim", log), Counter("observer", log), Counter("nav", log))
    scheduler.setup()
    outcome = scheduler.run(lambda: scheduler.rounds == 3)
    assert outcome.reason == "done" and outcome.rounds == 3
    assert [name for name, _ in log] == ["sim", "observer", "nav"] * 3
    assert [wall for _, wall in log] == pytest.approx([0.0] * 3 + [0.02] * 3 + [0.04] * 3)


def test_agents_that_wait_on_each_other_for_ever_are_reported_as_stalled() -> None:
    log: list[tuple[str, float]] = []
    scheduler = _scheduler(Counter("a", log, writes=False), Counter("b", log, writes=False))
    scheduler.setup()
    outcome = scheduler.run(lambda: False, stall_rounds=50)
    assert outcome.reason == "stalled" and outcome.rounds == 50


def test_an_agent_that_raises_is_named_and_every_agent_is_torn_down() -> None:
    log: list[tuple[str, float]] = []
    first, second = Counter("a", log), Counter("b", log, fail_at=4)
    scheduler = _scheduler(first, second)
    scheduler.setup()
    with pytest.raises(AgentError, match="agent b failed: ValueError: broken on purpose"):
        scheduler.run(lambda: False)
    scheduler.teardown()
    assert first.torn_down and second.torn_down


def test_the_clock_waits_for_the_perceivers_with_perception_in_lockstep(tmp_path: Path) -> None:
    """What makes a launch with walking people reproducible: the simulator publishes the next tick
    only once the observer, the agenda and the executive processed this one (their loops may lag)."""
    graph = DSRGraph(agent="test")
    wall = [0.0]
    sim = SimRobotAgent(AgentConfig(name="sim_robot", scene=TINY, run_dir=tmp_path,
                                    options={"perception_lockstep": "1", "busy_rate": "1", "watchdog_s": "30"}))
    sim.wall_clock = lambda: wall[0]   # type: ignore[method-assign]
    sim.setup(graph, Recorder("sim_robot", None, None))
    graph.insert_node(type="intention", name="intention/m/0", attrs={"state": "active", "kind": "navigate"})
    start = sim.now_s
    for _ in range(5):
        wall[0] += 0.5
        sim.step()
    assert sim.now_s == start, "no perceiver saw the first tick: the clock holds"
    for agent in LOCKSTEP:
        mark_observed(graph, agent, sim.now_s)
    wall[0] += 0.5
    sim.step()
    assert sim.now_s > start
    held = sim.now_s
    wall[0] += 0.5
    sim.step()
    assert sim.now_s == held, "the new tick is not perceived yet"
    wall[0] += 30.0
    sim.step()
    assert sim.now_s > held, "a perceiver silent for the watchdog's 30 s no longer holds the clock"


def test_options_are_the_lockstep_ones_then_the_callers() -> None:
    options = merged_options({"sim_robot": ["busy_rate=2", "seed=3"]}, rate=120.0)
    assert options["sim_robot"] == {"busy_rate": "2", "perception_lockstep": "1", "seed": "3", "rate": "120.0"}
    assert options["social_navigation"] == {"perception_lockstep": "1"}


def test_a_worker_with_other_scene_files_or_another_chronav_refuses_the_run() -> None:
    expected = sweep_fingerprint(str(TINY))
    check_worker(expected, str(TINY))
    edited = {**expected, "files": [{**expected["files"][0], "sha256": "0" * 64}]}
    with pytest.raises(WorkerMismatch, match="eval_tiny.yaml differs from the sweep's"):
        check_worker(edited, str(TINY))
    with pytest.raises(WorkerMismatch, match="runs chronav .* the sweep 0.0.0"):
        check_worker({**expected, "chronav": "0.0.0"}, str(TINY))


def test_launch_in_process_leaves_what_a_launch_leaves_and_repeats_itself(tmp_path: Path,
                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    import gc

    from dsr.collector import GC_THRESHOLDS

    monkeypatch.setenv("CHRONAV_RUNS", str(tmp_path))
    monkeypatch.setenv("RERUN", "on")
    runs = []
    thresholds = gc.get_threshold()
    gc.set_threshold(700, 10, 10)       # Python's own: the run raises them as a replica's process does
    try:
        for _ in range(2):
            result = CliRunner().invoke(app, ["launch", str(TINY), "--in-process", "--json"])
            assert result.exit_code == 0, result.output
            runs.append(json.loads(result.stdout))
        assert gc.get_threshold() == GC_THRESHOLDS
    finally:
        gc.set_threshold(*thresholds)
    first, second = runs
    assert first["ok"] and first["missions"]["cross"]["state"] == "done"
    assert first["missions"] == second["missions"]
    run_dir = Path(first["run_dir"])
    assert json.loads((run_dir / "result.json").read_text())["missions"] == first["missions"]
    assert Path(first["rrd"]).stat().st_size > 0
    for output in ("trajectory.csv", "people.csv"):
        assert (run_dir / output).read_bytes() == (Path(second["run_dir"]) / output).read_bytes()
    assert len((run_dir / "trajectory.csv").read_text().splitlines()) > 50

"""`chronav launch SCENE --in-process`: every registered agent in this process, in lockstep, on one graph.

Why beside tools/launch.py and not inside it: a launch supervises processes, a router and their
credentials; an in-process run has none of them, only the agents (the same classes, built from
the same ``AgentConfig`` a process would parse) and the scheduler of agents/runtime/lockstep.py.
What a run leaves behind is the same: ``<run>/trajectory.csv`` and ``people.csv`` (written by the
simulator agent), ``result.json`` in the launch's format, and, when recorded, the merged Rerun
recording ``<runs>/<run id>.rrd``.

The agents get the options that take wall time out of a run (``busy_rate=0``: the clock waits
while agents plan; ``perception_lockstep=1``: it moves on only once the perceivers saw the tick),
which ``chronav evaluate --mode launch`` passes to its processes too: the two modes then compute
the same run (tests/system/test_parity.py).
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from agents.world.vocabulary import MissionState, NodeType
from tools.launch import LaunchError, RunResult, agent_names, check_rate, check_timeout

if TYPE_CHECKING:
    from agents.runtime.lockstep import Lockstep
    from agents.runtime.recording import Recorder, RecordingFile
    from scenes.model import Scene

def round_order() -> tuple[str, ...]:
    """The order of a round, each registered agent's ``round_order`` (agents/lib/agent_plugins.py):
    the clock first, then who perceives the tick, then who acts on it."""
    return agent_names()


def lockstep_options() -> dict[str, list[str]]:
    """Each agent's options that make a run independent of wall time (also given to the processes
    of an evaluate launch), as its registration declares them."""
    from agents.world.vocabulary import vocabulary

    return {spec.name: list(spec.lockstep_options) for spec in vocabulary().agents if spec.lockstep_options}


def agent_classes(names: Sequence[str] | None = None) -> dict[str, type[Any]]:
    """The classes of the agents ``names`` (all registered ones by default), imported now.  A
    plug-in whose class cannot be imported (or is not its agent) is left out with a warning naming
    it, its package and why; the rest runs."""
    import logging

    from agents.lib.agent_plugins import agent_class
    from agents.lib.registry import RefusedExtension
    from agents.world.vocabulary import vocabulary

    vocab = vocabulary()
    classes: dict[str, type[Any]] = {}
    for name in agent_names() if names is None else names:
        try:
            classes[name] = agent_class(vocab.spec(name))
        except RefusedExtension as exc:
            logging.getLogger("chronav.plugins").warning("%s; the rest runs without it", exc)
    return classes


def build_agents(scene: Path, names: Sequence[str], *, graph_name: str = "chronav", run_dir: Path | None = None,
                 recording_id: str | None = None,
                 options: Mapping[str, Mapping[str, str]] | None = None) -> list[Any]:
    """The named agents as their processes build them: one ``AgentConfig`` each, ``options`` by name.

    Shared by ``run_in_process`` and the offline-agents harness (tools/offline_agents.py)."""
    from agents.runtime.config import AgentConfig

    classes = agent_classes(names)
    return [classes[name](AgentConfig(name=name, scene=scene, graph=graph_name, run_dir=run_dir,
                                      recording_id=recording_id, options=dict((options or {}).get(name, {}))))
            for name in names if name in classes]


def merged_options(agent_options: dict[str, list[str]] | None, rate: float | None) -> dict[str, dict[str, str]]:
    """Each agent's ``-o KEY=VALUE`` options as a dict: the lockstep ones, then the caller's."""
    merged: dict[str, dict[str, str]] = {name: {} for name in agent_names()}
    for source in (lockstep_options(), agent_options or {}):
        for name, items in source.items():
            for item in items:
                key, sep, value = item.partition("=")
                if not sep:
                    raise LaunchError(f"agent option {item!r} of {name}: expected KEY=VALUE")
                merged[name][key] = value
    if rate is not None:
        merged["sim_robot"]["rate"] = str(rate)
    return merged


def run_in_process(scene: str | Path, *, rate: float | None = None, runs_dir: Path | None = None,
                   timeout_s: float = 900.0, record: bool = True,
                   agent_options: dict[str, list[str]] | None = None,
                   on_tick: Callable[[dict[str, object]], None] | None = None,
                   stop: threading.Event | None = None) -> RunResult:
    """Run one scene with every agent in this process; the same result a launch returns.

    ``stop`` ends the run from another thread (Dask, a pool); in the main thread Ctrl-C does."""
    from agents.runtime.lockstep import AgentError
    from agents.world.scene_world import load_world
    from tools.launch import _make_run_dir, hourly_rotation, log_scene_static, realtime_run, write_final_graph
    from tools.system.runs import runs_dir as default_runs_dir

    check_rate(rate)
    check_timeout(timeout_s)
    from dsr.collector import tune_collector
    tune_collector()     # this process holds the run's replica: the collector policy of one that does
    loaded = load_world(scene)
    spec = loaded.scene
    run_id = f"{spec.name}-{datetime.now().strftime('%Y%m%d-%H%M%S')}-{os.getpid()}-{threading.get_ident() % 10000}"
    run_dir = _make_run_dir(runs_dir or default_runs_dir(), run_id)
    options = merged_options(agent_options, rate)
    record = record and os.environ.get("RERUN", "on") != "off"   # what the agents' Recorders honour too
    run = _InProcessRun(spec=spec, scene_path=loaded.path, run_id=run_id, run_dir=run_dir, record=record,
                        started=time.monotonic(), on_tick=on_tick)
    # A real-time run records hour by hour (its recording stream reads the setting when it is made).
    with hourly_rotation(realtime_run(rate, spec.clock.rate)):
        scheduler, launcher = _build_scheduler(run, options)
    error: str | None = None
    reason = "done"
    run.problems = scheduler.dropped      # agent plug-ins that raised and left the run, in the result
    try:
        if record:
            log_scene_static(launcher, spec)
        scheduler.setup()
        outcome = scheduler.run(lambda: run.done(scheduler.rounds), timeout_s=timeout_s, stop=stop)
        reason = outcome.reason
        if reason == "stalled":
            error = (f"the agents stopped making progress at round {outcome.rounds} (nothing changed in the graph "
                     f"for {outcome.rounds} rounds); see {run_dir}")
    except AgentError as exc:
        error = str(exc)
    finally:
        scheduler.teardown()
        launcher.close()
        if run.recording is not None:
            run.recording.close()
        write_final_graph(run.run_dir, run.graph)
    return _finish(run, reason, error)


class _InProcessRun:
    """One in-process run: where it writes, its graph, and the missions its watch last saw."""

    def __init__(self, *, spec: Scene, scene_path: Path, run_id: str, run_dir: Path, record: bool, started: float,
                 on_tick: Callable[[dict[str, object]], None] | None) -> None:
        from dsr import DSRGraph

        self.spec = spec
        self.scene_path = scene_path
        self.run_id = run_id
        self.run_dir = run_dir
        self.record = record
        self.started = started
        self.on_tick = on_tick
        self.graph = DSRGraph(agent="lockstep", graph=run_id.replace(".", "_"))
        self.missions: dict[str, dict[str, object]] = {}
        #: the agents of the run, in round order (set once they are built)
        self.agents: tuple[str, ...] = ()
        #: agent -> what keeps it from its job (an agent plug-in that raised and left the run)
        self.problems: dict[str, str] = {}
        #: the one recording stream of the run's agents and launcher (None when not recording)
        self.recording: RecordingFile | None = None

    def status(self) -> dict[str, object]:
        """What a launch hands ``on_tick``: clock, missions, agents, wall time, where the run is."""
        from dsr.attr_values import as_float

        graph = self.graph
        clock = graph.get_node_by_name("clock")
        found = {str(n.attrs.get("mission_id", n.name)): dict(n.attrs) for n in graph.nodes_of_type(NodeType.MISSION)}
        return {"now_s": None if clock is None else as_float(clock.attrs.get("now_s", 0.0)),
                "clock_mode": None if clock is None else clock.attrs.get("mode"),
                "clock_finished": bool(clock is not None and clock.attrs.get("finished")),
                "missions": found, "agents": {name: ("up", 0) for name in self.agents}, "dsr": graph.counts(),
                "wall_s": time.monotonic() - self.started,
                "run": {"run_dir": str(self.run_dir), "endpoint": "in-process", "graph": graph.graph_name}}

    def done(self, rounds: int) -> bool:
        """The scheduler's stop test after each round: the clock finished or every mission ended
        (``on_tick`` gets the status every 50 rounds; tombstones are forgotten as often)."""
        if rounds % 50 == 0:
            self.graph.compact(_sole_replica)
        current = self.status()
        self.missions = current["missions"]  # type: ignore[assignment]
        missions = self.missions
        if self.on_tick is not None and rounds % 50 == 0:
            self.on_tick(current)
        return bool(current["clock_finished"]) or (
            len(missions) == len(self.spec.missions) and bool(missions)
            and all(m.get("state") in MissionState.TERMINAL for m in missions.values()))


def _sole_replica(_replica: int, _hlc: int) -> bool:
    """Compaction's "has every member seen this write": in-process the agents share one graph, the
    only replica, so every member has seen every write once it is made, and a removal's tombstone
    can be forgotten at once (launched, the transport waits for every member's digest).  Without
    it an in-process day kept every tombstone of the day (long runs, docs/long_runs.md)."""
    return True


def _build_scheduler(run: _InProcessRun, options: dict[str, dict[str, str]]) -> tuple[Lockstep, Recorder]:
    """The agents, one recorder each, the lockstep scheduler over them, and the launcher's recorder."""
    from agents.runtime.lockstep import Lockstep
    from agents.runtime.recording import Recorder, shared_recording_file
    from agents.world.write_policy import policy_from_env

    recording_id = run.run_id if run.record else None
    recording_dir = run.run_dir if run.record else None
    agents = build_agents(run.scene_path.resolve(), round_order(), graph_name=run.graph.graph_name,
                          run_dir=run.run_dir, recording_id=recording_id, options=options)
    run.agents = tuple(agent.config.name for agent in agents)
    # One stream for every agent and the launcher: each logs under its own entities, and the
    # Rerun SDK never frees a stream (agents/runtime/recording.py, RecordingFile).
    run.recording = shared_recording_file("inprocess", recording_dir, recording_id)
    recorders = [Recorder(name, recording_dir, recording_id, day=run.spec.clock.date, file=run.recording)
                 for name in run.agents]
    scheduler = Lockstep(run.graph, agents, recorders, policy=policy_from_env())
    launcher = Recorder("launcher", recording_dir, recording_id, day=run.spec.clock.date, file=run.recording)
    return scheduler, launcher


def _finish(run: _InProcessRun, reason: str, error: str | None) -> RunResult:
    """Merge the recordings, write ``result.json`` in the launch's format; the run's result."""
    from tools.launch import _write_result, merge_run_recording, scene_missions

    rrd_path: Path | None = None
    hours: list[dict[str, Any]] = []
    if run.record:
        rrd_path, hours = merge_run_recording(run.run_dir, run.run_id)
    result = RunResult(scene=run.spec.name, run_dir=run.run_dir, rrd_path=rrd_path, hours=hours,
                       missions={**scene_missions(run.spec), **run.missions}, events=[],
                       restarts={name: 0 for name in run.agents}, wall_s=time.monotonic() - run.started,
                       interrupted=reason == "interrupted", timed_out=reason == "timed_out",
                       scene_path=run.scene_path, error=error, problems=dict(run.problems))
    _write_result(result)
    return result



"""`chronav launch SCENE` / `chronav demo`: the whole system, one process per agent.

Order matters (see shared notes): the Zenoh router first (agents in client mode fail at once if
no router listens), then the agents; the launcher joins the graph itself only to watch missions,
clock and health.  At the end the per-agent recordings are merged into ONE ``.rrd``.

A run belongs to the user who started it (tools/system/runs.py): its directory goes under
``./recordings`` of the current directory (or ``$CHRONAV_RUNS``), its router requires the run's
own credentials (one Zenoh user per agent, an ACL giving each agent's key space to that user
alone), and ``connect.json`` (mode 0600) tells the owner's tools how to join.

However the run ends (missions done, timeout, Ctrl-C, no trajectory at all, an agent that gave
up), the agents are stopped, the recordings merged, ``result.json`` written and a result
returned: the loop's exits are all ``break``s, and the finishing work sits in ``finally``.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any


from tools.ports import free_port, wait_for_port
from tools.system.runs import prepare_run_security, runs_dir as default_runs_dir, write_connect_file
from tools.system.supervisor import ProgressWatch, Supervisor

AGENTS: tuple[str, ...] = ("sim_robot", "object_recognition", "human_observer", "agenda", "social_navigation",
                           "executive")
#: started with `--ros` (agents/ros_bridge): the run's topics over rmw_zenoh, /goal_pose -> missions
ROS_BRIDGE = "ros_bridge"
DEFAULT_SCENE = "icra_usecase"
NOT_STARTED = "not started"
#: an agent whose heartbeat stops for this long (wall s) is killed and restarted
DEFAULT_HANG_TIMEOUT_S = 60.0
#: time from an agent's (re)start to its first heartbeat (imports, numba compilation, joining)
DEFAULT_STARTUP_TIMEOUT_S = 180.0
#: Zenoh variables a run sets itself; inherited ones (a deployment's user, TLS files, endpoints)
#: would point the agents somewhere else or clash with the run's credentials
_RUN_OWNED_PREFIX = "CHRONAV_ZENOH_"
_INHERITED_ZENOH = ("CHRONAV_ZENOH_LEASE_MS",)


class LaunchError(Exception):
    """The run could not be started as asked (bad option, unwritable directory, no router)."""


@dataclass
class RunResult:
    scene: str
    run_dir: Path
    rrd_path: Path | None
    missions: dict[str, dict[str, object]]
    events: list[str]
    restarts: dict[str, int]
    wall_s: float
    interrupted: bool = False
    timed_out: bool = False
    metrics: dict[str, object] = field(default_factory=dict)
    scene_path: Path | None = None
    error: str | None = None

    @property
    def ok(self) -> bool:
        from agents.world.vocabulary import MissionState
        return (not self.interrupted and not self.timed_out and self.error is None and bool(self.missions)
                and all(m.get("state") == MissionState.DONE for m in self.missions.values()))

    @property
    def missions_done(self) -> int:
        from agents.world.vocabulary import MissionState
        return sum(1 for m in self.missions.values() if m.get("state") == MissionState.DONE)


def check_rate(rate: float | None, option: str = "--rate") -> float | None:
    """--rate: sim seconds per wall second, finite and > 0 (None: the scene's own)."""
    if rate is not None and (not math.isfinite(rate) or rate <= 0):
        raise LaunchError(f"{option} {rate:g}: give the sim seconds per wall second as a number greater than 0 "
                          "(e.g. 1 for real time, 60 for a minute a second), or leave it out for the scene's rate")
    return rate


def check_timeout(value: float, option: str = "--timeout") -> float:
    """A wall-clock limit in seconds: finite and > 0."""
    if not math.isfinite(value) or value <= 0:
        raise LaunchError(f"{option} {value:g}: give a number of wall seconds greater than 0")
    return value


def rerun_binary() -> Path:
    """The real viewer/CLI binary inside the wheel (the console script is a Python wrapper)."""
    import rerun_cli

    return Path(rerun_cli.__file__).parent / "rerun"


def merge_recordings(parts: list[Path], out: Path) -> Path | None:
    """`rerun rrd optimize` = merge + compaction + footer; parts of killed agents are accepted."""
    if not parts:
        return None
    try:
        result = subprocess.run([str(rerun_binary()), "rrd", "optimize", *map(str, parts), "-o", str(out)],
                                capture_output=True, text=True, timeout=300, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        sys.stderr.write(f"warning: could not merge recordings: {exc}\n")
        return None
    if result.returncode != 0 or not out.exists():
        sys.stderr.write(f"warning: could not merge recordings: {result.stderr.strip()[-500:]}\n")
        return None
    return out


def write_pids(run_dir: Path, supervisor: Supervisor, router_pid: int | None) -> None:
    """pids.json lets fault tests (and operators) find and kill a given agent."""
    pids: dict[str, int | None] = {name: m.pid for name, m in supervisor.processes.items()}
    pids["router"] = router_pid
    tmp = run_dir / "pids.json.tmp"
    tmp.write_text(json.dumps(pids))
    tmp.replace(run_dir / "pids.json")


def run_environment(endpoint: str, graph: str, run_id: str, record: bool) -> dict[str, str]:
    """The agents' environment: the launcher's, minus any Zenoh identity or endpoint it holds."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(_RUN_OWNED_PREFIX) or k in _INHERITED_ZENOH}
    env.update({"CHRONAV_ZENOH_CONNECT": endpoint, "CHRONAV_ZENOH_MODE": "client", "CHRONAV_GRAPH": graph,
                "CHRONAV_RECORDING_ID": run_id, "PYTHONUNBUFFERED": "1", "CHRONAV_EXIT_WITH_PARENT": "1"})
    if not record:
        env["RERUN"] = "off"
    return env


def scene_missions(spec: Any) -> dict[str, dict[str, object]]:
    """Every mission of the scene as not started: what the table shows for missions the executive
    never published (a run stopped in its first seconds)."""
    from scenes.clock import parse_clock

    return {m.id: {"mission_id": m.id, "goal": m.goal_text(), "time_s": parse_clock(m.time), "state": NOT_STARTED}
            for m in spec.missions}


def _make_run_dir(directory: Path, run_id: str) -> Path:
    run_dir = directory / run_id
    try:
        run_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise LaunchError(f"cannot create the run directory {run_dir}: {exc.strerror}; run from a directory "
                          "you can write to, or set CHRONAV_RUNS") from None
    return run_dir


def log_scene_static(recorder: Any, spec: Any) -> None:
    """What a run's recording holds before any agent logs: the blueprint framed on the scene, the
    world frame, the walls and the legend. One definition for a launch and an in-process run."""
    from agents.runtime.drawing.layout import blueprint, log_legend, world_frame
    from agents.runtime.drawing.social_map import log_walls

    recorder.send_blueprint(blueprint(spec))
    world_frame(recorder)
    log_walls(recorder, [[list(p) for p in wall] for wall in spec.walls])
    log_legend(recorder, spec)


def run_system(scene: str | Path, *, rate: float | None = None, runs_dir: Path | None = None,
               timeout_s: float = 900.0, record: bool = True, restart_limit: int = 3,
               hang_timeout_s: float = DEFAULT_HANG_TIMEOUT_S,
               startup_timeout_s: float = DEFAULT_STARTUP_TIMEOUT_S,
               agent_options: dict[str, list[str]] | None = None,
               on_tick: Callable[[dict[str, object]], None] | None = None,
               metrics_report: bool = True, ros_domain: int | None = None, robot: str = "sim") -> RunResult:
    """Run one scene end to end; return when every mission is done or failed, or on timeout/Ctrl-C.

    ``metrics_report=False`` skips the social-vs-baseline metrics the demo logs into the recording
    (``chronav evaluate`` measures each run itself, whatever its planner).  ``ros_domain`` adds
    the ROS 2 bridge agent on that ROS_DOMAIN_ID; ``robot="ros"`` drives a ROS 2 robot through it
    instead of the simulated one (docs/ros2.md)."""
    from agents.world.vocabulary import MissionState
    from agents.runtime.heartbeat import read_stamp
    from agents.runtime.recording import Recorder
    from dsr import DSRError, join
    from dsr.config import ZenohSettings
    from agents.world.write_policy import policy_from_env
    from agents.world.scene_world import load_world
    from agents.runtime.drawing.dsr_graph import GraphLogger

    check_rate(rate)
    if robot not in ("sim", "ros"):
        raise LaunchError(f"--robot {robot!r}: give sim (the simulated robot) or ros (a ROS 2 robot through --ros)")
    if robot == "ros" and ros_domain is None:
        raise LaunchError("--robot ros needs the ROS 2 bridge: add --ros (and --ros-domain N if not 0)")
    check_timeout(timeout_s)
    check_timeout(hang_timeout_s, "--hang-timeout")
    check_timeout(startup_timeout_s, "--startup-timeout")
    loaded = load_world(scene)
    spec = loaded.scene
    policy = policy_from_env()  # fail before any process starts if the write policy is broken
    run_id = f"{spec.name}-{datetime.now().strftime('%Y%m%d-%H%M%S')}-{os.getpid()}"
    graph_name = run_id.replace(".", "_")
    run_dir = _make_run_dir(runs_dir or default_runs_dir(), run_id)
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    agents = AGENTS if ros_domain is None else (*AGENTS, ROS_BRIDGE)
    # the bridge's identity always: `chronav ros bridge --run` may join the run later
    security = prepare_run_security(run_dir, graph_name, (*AGENTS, ROS_BRIDGE))
    env = run_environment(endpoint, graph_name, run_id, record)
    supervisor = Supervisor(run_dir / "logs", env, restart_limit=restart_limit)
    router = supervisor.add("router", "dsr.router", ["--listen", endpoint, *security.router_args()])
    common = ["--scene", str(loaded.path.resolve()), "--run-dir", str(run_dir), "--recording-id", run_id]
    for name in agents:
        options = [*(["-o", f"rate={rate}"] if rate is not None and name == "sim_robot" else [])]
        options += ["-o", f"ros_domain={ros_domain}"] if name == ROS_BRIDGE else []
        options += ["-o", "robot=ros"] if robot == "ros" and name in ("sim_robot", ROS_BRIDGE) else []
        for opt in (agent_options or {}).get(name, []):
            options += ["-o", opt]
        supervisor.add(name, f"agents.{name}", [*common, *options], env=security.agent_env(name))
    watch = ProgressWatch(hang_s=hang_timeout_s, startup_s=startup_timeout_s)

    started = time.monotonic()
    interrupted = timed_out = False
    error: str | None = None
    previous_sigint = signal.getsignal(signal.SIGINT)
    stop_requested = {"flag": False}

    def on_sigint(_signum: int, _frame: object) -> None:
        stop_requested["flag"] = True

    signal.signal(signal.SIGINT, on_sigint)
    previous_sigterm = signal.signal(signal.SIGTERM, on_sigint)  # stopped by a supervisor: clean up too
    missions: dict[str, dict[str, object]] = {}
    metrics: dict[str, object] = {}
    recorder = Recorder("launcher", run_dir if record else None, run_id, day=spec.clock.date)
    rrd_path: Path | None = None
    try:
        log_scene_static(recorder, spec)
        supervisor.start("router")
        if not wait_for_port(port, 15, give_up=lambda: stop_requested["flag"] or not router.alive):
            if not stop_requested["flag"]:
                raise LaunchError(f"the Zenoh router did not listen on {endpoint}; see {router.log_path}")
        else:
            write_connect_file(run_dir, run_id=run_id, endpoint=endpoint, graph=graph_name, security=security)
            for name in agents:
                supervisor.start(name)
            write_pids(run_dir, supervisor, router.pid)
            settings = ZenohSettings.from_env({**env, "CHRONAV_ZENOH_USER": security.reader.user,
                                               "CHRONAV_ZENOH_PASSWORD": security.reader.password})
            # Read-only: the launcher only watches; it enforces the agents' write policy too.
            with join(agent="launcher", graph=graph_name, settings=settings, read_only=True,
                      policy=policy) as graph:
                graph_logger = GraphLogger(recorder)
                status: dict[str, Any] = {}
                while True:
                    graph.dispatch(timeout=0.1)
                    changed = bool(supervisor.poll())
                    changed |= _restart_stuck(graph, supervisor, watch, read_stamp)
                    if changed:
                        write_pids(run_dir, supervisor, router.pid)
                    status = _status(graph, supervisor, started)
                    status["run"] = {"run_dir": str(run_dir), "endpoint": endpoint, "graph": graph_name}
                    missions = status["missions"]
                    graph_logger.maybe_log(graph, status.get("now_s"))
                    if on_tick is not None:
                        on_tick(status)
                    if stop_requested["flag"]:
                        interrupted = True
                        break
                    if len(missions) == len(spec.missions) and missions and all(
                            m.get("state") in MissionState.TERMINAL for m in missions.values()):
                        break
                    if status.get("clock_finished"):
                        break
                    if time.monotonic() - started > timeout_s:
                        timed_out = True
                        break
                    if supervisor.given_up():
                        break
                graph_logger.maybe_log(graph, status.get("now_s"), force=True)
        interrupted = interrupted or stop_requested["flag"]
        if record and metrics_report and not interrupted:
            metrics = _report(loaded.path, run_dir, missions, recorder)
    except (LaunchError, DSRError) as exc:    # e.g. the launcher could not join its own router
        error = str(exc)
    finally:
        # Still under our handlers: a second Ctrl-C must not cut the clean-up short.
        try:
            supervisor.stop_all(order=[*reversed(agents), "router"])
            recorder.close()
            if record:
                rrd_path = merge_recordings(sorted((run_dir / "rrd").glob("*.rrd")),
                                            run_dir.parent / f"{run_id}.rrd")
            missions = {**scene_missions(spec), **missions}
            result = RunResult(scene=spec.name, run_dir=run_dir, rrd_path=rrd_path, missions=missions,
                               events=list(supervisor.events),
                               restarts={n: m.restarts for n, m in supervisor.processes.items()},
                               wall_s=time.monotonic() - started, interrupted=interrupted, timed_out=timed_out,
                               metrics=metrics, scene_path=loaded.path, error=error)
            _write_result(result)
        finally:
            signal.signal(signal.SIGINT, previous_sigint)
            signal.signal(signal.SIGTERM, previous_sigterm)
    return result


def _restart_stuck(graph: Any, supervisor: Supervisor, watch: ProgressWatch,
                   read_stamp: Callable[[Any, str], tuple[int, int] | None]) -> bool:
    """Kill the agents whose heartbeat stopped (the next poll restarts them); True if any."""
    now = time.monotonic()
    killed = False
    for name in [n for n in supervisor.processes if n != "router"]:   # the agents, the ROS bridge too
        managed = supervisor.processes[name]
        if managed.pid is None or not managed.alive:
            continue
        watch.observe(name, managed.pid, read_stamp(graph, name), now)
        reason = watch.overdue(name, now)
        if reason is not None:
            supervisor.restart_stuck(name, reason)
            killed = True
    if killed:
        supervisor.poll()
    return killed


def _report(scene_path: Path, run_dir: Path, missions: dict[str, dict[str, object]], recorder: Any
            ) -> dict[str, object]:
    """Metrics of the day (social vs baseline) as scalars in this same recording."""
    from tools.system.report import build_report, log_report

    metrics = build_report(scene_path, run_dir, missions)
    log_report(recorder, metrics, missions)
    return metrics


def _write_result(result: RunResult) -> None:
    (result.run_dir / "result.json").write_text(json.dumps({
        "scene": result.scene, "ok": result.ok, "missions": result.missions, "events": result.events,
        "restarts": result.restarts, "wall_s": result.wall_s, "rrd": str(result.rrd_path) if result.rrd_path else None,
        "interrupted": result.interrupted, "timed_out": result.timed_out, "error": result.error,
        "scene_path": str(result.scene_path.resolve()) if result.scene_path else None}, indent=2))


def _status(graph, supervisor: Supervisor, started: float) -> dict[str, object]:
    from agents.world.vocabulary import NodeType
    clock = graph.get_node_by_name("clock")
    missions = {}
    for node in graph.nodes_of_type(NodeType.MISSION):
        missions[str(node.attrs.get("mission_id", node.name))] = dict(node.attrs)
    return {
        "now_s": None if clock is None else float(clock.attrs.get("now_s", 0.0)),
        "clock_mode": None if clock is None else clock.attrs.get("mode"),
        "clock_finished": bool(clock is not None and clock.attrs.get("finished")),
        "missions": missions,
        "agents": {name: ("up" if m.alive else "down", m.restarts) for name, m in supervisor.processes.items()},
        "pids": {name: m.pid for name, m in supervisor.processes.items()},  # fault injection (tools/chaos/command.py)
        "wall_s": time.monotonic() - started,
    }

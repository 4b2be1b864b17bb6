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

import contextlib
import json
import math
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any


from tools.ports import free_port, wait_for_port
from tools.system.restart_budget import RestartBudget
from tools.system.runs import RunSecurity, prepare_run_security, runs_dir as default_runs_dir, write_connect_file
from tools.system.supervisor import ManagedProcess, ProgressWatch, Supervisor

if TYPE_CHECKING:
    from agents.lib.agent_plugins import AgentSpec
    from agents.runtime.recording import Recorder

#: started with `--ros` (agents/ros_bridge): the run's topics over rmw_zenoh, /goal_pose -> missions
ROS_BRIDGE = "ros_bridge"
DEFAULT_SCENE = "icra_usecase"
#: the graph as a run ended, in the run directory (write_final_graph)
FINAL_GRAPH = "graph.json"
NOT_STARTED = "not started"
#: an agent whose heartbeat stops for this long (wall s) is killed and restarted
DEFAULT_HANG_TIMEOUT_S = 60.0
#: time from an agent's (re)start to its first heartbeat (imports, numba compilation, joining)
DEFAULT_STARTUP_TIMEOUT_S = 180.0
#: Zenoh variables a run sets itself; inherited ones (a deployment's user, TLS files, endpoints)
#: would point the agents somewhere else or clash with the run's credentials
_RUN_OWNED_PREFIX = "CHRONAV_ZENOH_"
_INHERITED_ZENOH = ("CHRONAV_ZENOH_LEASE_MS",)
#: real-time runs (a rate of 1 or less, a ROS robot) rotate their recording every hour of sim time
HOUR_S = 3600.0


class LaunchError(Exception):
    """The run could not be started as asked (bad option, unwritable directory, no router)."""


def agent_names() -> tuple[str, ...]:
    """The agents a run starts, in round order: every agent registered through the ``chronav.agents``
    entry points (chronav's six and the installed plug-ins) that was not refused at start (each
    refusal is logged as a warning naming the plug-in, its package and why).  Why a function: the
    registry is read on the first launch, not when ``chronav --help`` imports this module."""
    from agents.world.vocabulary import vocabulary

    return vocabulary().names


def process_agents() -> tuple[AgentSpec, ...]:
    """The agents a launch runs as processes: ``agent_names()``'s, less a plug-in whose process module
    cannot be found (refused with a warning naming it, its package and why; the rest runs)."""
    import logging

    from agents.lib.agent_plugins import process_missing
    from agents.world.vocabulary import vocabulary

    found = []
    for spec in vocabulary().agents:
        refusal = process_missing(spec)
        if refusal is None:
            found.append(spec)
        else:
            logging.getLogger("chronav.plugins").warning("%s; the rest runs without it", refusal)
    return tuple(found)


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
    #: what an agent still reported as keeping it from its job when the run ended (agent -> words)
    problems: dict[str, str] = field(default_factory=dict)
    #: every restart of this run: agent, reason, wall time (tools/system/restart_budget.py)
    restart_log: list[dict[str, object]] = field(default_factory=list)
    #: a real-time run's recording, one file per hour in place of ``rrd_path``: hour ("09:00"),
    #: start_s, rrd (a path) each (``hourly_recordings``)
    hours: list[dict[str, Any]] = field(default_factory=list)

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


def merge_recordings(parts: list[Path], out: Path, remove_parts: bool | None = None) -> Path | None:
    """`rerun rrd optimize` = merge + compaction + footer; parts of killed agents are accepted.

    Written to a hidden partial file and renamed: a disk that fills during the merge leaves no
    half-written recording under the run's name (the partial file is removed). Once merged the
    per-agent parts are removed (they held 39 MB beside the 12 MB merged file of a center_day
    run); a failed merge keeps them, to open or merge by hand. ``remove_parts`` None: removed
    unless they are rotated parts (``-sNNN``, agents/runtime/recording.py), which a long run then
    merges hour by hour itself (tools/week.py)."""
    if not parts:
        return None
    if remove_parts is None:
        from agents.runtime.recording import part_slot

        remove_parts = all(part_slot(part) is None for part in parts)
    partial = out.with_name(f".{out.stem}.partial{out.suffix}")
    try:
        result = subprocess.run([str(rerun_binary()), "rrd", "optimize", *map(str, parts), "-o", str(partial)],
                                capture_output=True, text=True, timeout=300, check=False)
        if result.returncode == 0 and partial.exists():
            os.replace(partial, out)
    except (OSError, subprocess.TimeoutExpired) as exc:
        partial.unlink(missing_ok=True)
        sys.stderr.write(f"warning: could not merge recordings: {exc}\n")
        return None
    if result.returncode != 0 or not out.exists():
        partial.unlink(missing_ok=True)
        sys.stderr.write(f"warning: could not merge recordings: {result.stderr.strip()[-500:]}\n")
        return None
    if remove_parts:
        remove_recording_parts(parts)
    return out


def remove_recording_parts(parts: list[Path]) -> None:
    """The per-agent parts, once merged, and their folder when nothing else lives there."""
    for part in parts:
        part.unlink(missing_ok=True)
    for folder in {part.parent for part in parts}:
        with contextlib.suppress(OSError):    # not empty: something else lives there, keep it
            folder.rmdir()


@contextlib.contextmanager
def hourly_rotation(realtime: bool) -> Iterator[None]:
    """With ``realtime``, the recorders made and the agents started inside (processes inherit the
    variable) rotate their recording parts every hour of sim time (agents/runtime/recording.py); a
    value the user set, or an enclosing run of days, is kept."""
    from agents.runtime.recording import ROTATE_ENV

    if not realtime or ROTATE_ENV in os.environ:
        yield
        return
    os.environ[ROTATE_ENV] = str(HOUR_S)
    try:
        yield
    finally:
        os.environ.pop(ROTATE_ENV, None)


def realtime_run(rate: float | None, scene_rate: float, robot: str = "sim") -> bool:
    """Whether a run is real time (a rate of 1 or less, or a ROS robot), whose recording rotates
    every hour (docs/long_runs.md)."""
    return robot == "ros" or (rate if rate is not None else scene_rate) <= 1.0


def merge_run_recording(run_dir: Path, run_id: str) -> tuple[Path | None, list[dict[str, Any]]]:
    """A finished run's parts merged: ``(<runs>/<run id>.rrd, [])``, or, when the parts were rotated
    over more than one hour (a long real-time run), ``(None, hours)``: one file per hour
    (``hourly_recordings``).  A real-time run within one hour keeps the one file every run has."""
    from agents.runtime.recording import part_slot

    parts = sorted((run_dir / "rrd").glob("*.rrd"))
    out = run_dir.parent / f"{run_id}.rrd"
    if len({part_slot(part) for part in parts} - {None}) <= 1:
        return merge_recordings(parts, out, remove_parts=True), []
    hours = hourly_recordings(parts, run_dir.name, run_dir.parent)
    if hours:
        return None, hours
    return merge_recordings(parts, out), []   # no hour could be merged: one file, the parts kept


def hourly_recordings(parts: list[Path], run_name: str, out_dir: Path) -> list[dict[str, Any]]:
    """A real-time run's recording parts as one file per hour in ``out_dir``, ``<run>-hNN.rrd``,
    each merged from the agents' parts of that hour with the rows logged before the clock was set."""
    from agents.runtime.recording import part_slot

    by_hour: dict[int, list[Path]] = {}
    unslotted: list[Path] = []
    for part in parts:
        slot = part_slot(part)
        (unslotted if slot is None else by_hour.setdefault(slot, [])).append(part)
    hours = []
    for slot, hour_parts in sorted(by_hour.items()):
        # unrotated parts hold rows logged without a clock (the scene's walls and legend, by an
        # in-process run's launcher): every hour opens with them
        out = merge_recordings([*unslotted, *hour_parts], out_dir / f"{run_name}-h{slot:02d}.rrd",
                               remove_parts=False)
        if out is not None:
            hours.append({"hour": f"{slot % 24:02d}:00", "start_s": slot * HOUR_S, "rrd": out})
    if by_hour and len(hours) == len(by_hour):   # every hour merged: the parts have served (a failed one keeps them)
        remove_recording_parts([*unslotted, *(p for hour_parts in by_hour.values() for p in hour_parts)])
    return hours


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


@dataclass
class _Run:
    """One launch: what is prepared before any process starts, then what the watch finds."""
    spec: Any
    scene_path: Path
    policy: Any
    run_id: str
    graph_name: str
    run_dir: Path
    port: int
    endpoint: str
    agents: tuple[str, ...]
    security: RunSecurity
    env: dict[str, str]
    supervisor: Supervisor
    router: ManagedProcess
    record: bool
    started: float = 0.0
    restart_log_from: int = 0       # the shared budget's log before this run (a long run's earlier days)
    missions: dict[str, dict[str, object]] = field(default_factory=dict)
    metrics: dict[str, object] = field(default_factory=dict)
    problems: dict[str, str] = field(default_factory=dict)
    interrupted: bool = False
    timed_out: bool = False
    error: str | None = None


class _StopRequest:
    """Ctrl-C, or SIGTERM (a supervisor stopping the launcher), asks the watch loop to end; the run
    then cleans up.  Installed on creation, the previous handlers put back by ``restore``."""

    def __init__(self) -> None:
        self.requested = False
        self._previous_sigint = signal.getsignal(signal.SIGINT)
        signal.signal(signal.SIGINT, self._on_signal)
        self._previous_sigterm = signal.signal(signal.SIGTERM, self._on_signal)

    def _on_signal(self, _signum: int, _frame: object) -> None:
        self.requested = True

    def restore(self) -> None:
        signal.signal(signal.SIGINT, self._previous_sigint)
        signal.signal(signal.SIGTERM, self._previous_sigterm)


def run_system(scene: str | Path, *, rate: float | None = None, runs_dir: Path | None = None,
               timeout_s: float = 900.0, record: bool = True, restart_limit: int = 3,
               hang_timeout_s: float = DEFAULT_HANG_TIMEOUT_S,
               startup_timeout_s: float = DEFAULT_STARTUP_TIMEOUT_S,
               agent_options: dict[str, list[str]] | None = None,
               on_tick: Callable[[dict[str, object]], None] | None = None,
               metrics_report: bool = True, ros_domain: int | None = None, robot: str = "sim",
               restart_budget: RestartBudget | None = None, settle_s: float = 0.0) -> RunResult:
    """Run one scene end to end; return when every mission is done or failed, or on timeout/Ctrl-C.

    ``metrics_report=False`` skips the social-vs-baseline metrics the demo logs into the recording
    (``chronav evaluate`` measures each run itself, whatever its planner).  ``ros_domain`` adds
    the ROS 2 bridge agent on that ROS_DOMAIN_ID; ``robot="ros"`` drives a ROS 2 robot through it
    instead of the simulated one (docs/ros2.md).  ``restart_budget``: one shared by the days of a
    long run (restarts per rolling hour, tools/system/restart_budget.py).  ``settle_s``: at a run's
    normal end, how long the watch may wait for the last removals' tombstones to be forgotten before
    its last status (a long run's per-day DSR counts, tools/week.py)."""
    from agents.runtime.recording import ROTATE_ENV, Recorder
    from dsr import DSRError

    _check_options(rate=rate, robot=robot, ros_domain=ros_domain, timeout_s=timeout_s,
                   hang_timeout_s=hang_timeout_s, startup_timeout_s=startup_timeout_s)
    run = _prepare_run(scene, rate=rate, runs_dir=runs_dir, record=record, restart_limit=restart_limit,
                       agent_options=agent_options, ros_domain=ros_domain, robot=robot,
                       restart_budget=restart_budget)
    watch = ProgressWatch(hang_s=hang_timeout_s, startup_s=startup_timeout_s)
    run.started = time.monotonic()
    stop = _StopRequest()
    # A real-time run records hour by hour, as each day of a long run does (the agents and this
    # launcher's recorder read the setting when they start).
    rotation = contextlib.ExitStack()
    rotation.enter_context(hourly_rotation(ROTATE_ENV in run.env))   # as its agents (_prepare_run)
    recorder = Recorder("launcher", run.run_dir if record else None, run.run_id, day=run.spec.clock.date)
    try:
        log_scene_static(recorder, run.spec)
        if _start_processes(run, stop):
            _watch_until_over(run, stop, watch, recorder, timeout_s=timeout_s, on_tick=on_tick, settle_s=settle_s)
        run.interrupted = run.interrupted or stop.requested
        if record and metrics_report and not run.interrupted:
            run.metrics = _report(run.scene_path, run.run_dir, run.missions, recorder)
    except (LaunchError, DSRError) as exc:    # e.g. the launcher could not join its own router
        run.error = str(exc)
    finally:
        # Still under our handlers: a second Ctrl-C must not cut the clean-up short.
        try:
            result = _finish(run, recorder)
        finally:
            stop.restore()
            rotation.close()
    return result


def _check_options(*, rate: float | None, robot: str, ros_domain: int | None, timeout_s: float,
                   hang_timeout_s: float, startup_timeout_s: float) -> None:
    """Refuse bad options before anything is read or started."""
    check_rate(rate)
    if robot not in ("sim", "ros"):
        raise LaunchError(f"--robot {robot!r}: give sim (the simulated robot) or ros (a ROS 2 robot through --ros)")
    if robot == "ros" and ros_domain is None:
        raise LaunchError("--robot ros needs the ROS 2 bridge: add --ros (and --ros-domain N if not 0)")
    check_timeout(timeout_s)
    check_timeout(hang_timeout_s, "--hang-timeout")
    check_timeout(startup_timeout_s, "--startup-timeout")
    check_log_rotation(os.environ)


def _prepare_run(scene: str | Path, *, rate: float | None, runs_dir: Path | None, record: bool,
                 restart_limit: int, agent_options: dict[str, list[str]] | None, ros_domain: int | None,
                 robot: str, restart_budget: RestartBudget | None = None) -> _Run:
    """Load the scene and the write policy, make the run directory, credentials and environment,
    and register the router and the agents with a supervisor (none started yet)."""
    from agents.world.write_policy import policy_from_env
    from agents.world.scene_world import load_world

    loaded = load_world(scene)
    spec = loaded.scene
    policy = policy_from_env()  # fail before any process starts if the write policy is broken
    run_id = f"{spec.name}-{datetime.now().strftime('%Y%m%d-%H%M%S')}-{os.getpid()}"
    graph_name = run_id.replace(".", "_")
    run_dir = _make_run_dir(runs_dir or default_runs_dir(), run_id)
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    processes = {spec.name: spec.process for spec in process_agents()}
    if ros_domain is not None:
        processes[ROS_BRIDGE] = f"agents.{ROS_BRIDGE}"
    agents = tuple(processes)
    # the bridge's identity always: `chronav ros bridge --run` may join the run later
    security = prepare_run_security(run_dir, graph_name, (*agent_names(), ROS_BRIDGE))
    env = run_environment(endpoint, graph_name, run_id, record)
    if realtime_run(rate, spec.clock.rate, robot):
        # Its agents record hour by hour (the launcher's own recorder follows this environment:
        # launch_scene; a run of days has set the variable already).
        # Each process cuts its log on the wall clock's hours (dsr/log_rotation.py).
        from agents.runtime.recording import ROTATE_ENV
        from dsr.log_rotation import LOG_ROTATE_ENV

        env.setdefault(ROTATE_ENV, str(HOUR_S))
        env.setdefault(LOG_ROTATE_ENV, str(int(HOUR_S)))
    supervisor = Supervisor(run_dir / "logs", env, restart_limit=restart_limit, budget=restart_budget)
    router = supervisor.add("router", "dsr.router", ["--listen", endpoint, *security.router_args()])
    common = ["--scene", str(loaded.path.resolve()), "--run-dir", str(run_dir), "--recording-id", run_id]
    for name in agents:
        options = _agent_options(name, rate=rate, ros_domain=ros_domain, robot=robot,
                                 extra=(agent_options or {}).get(name, []))
        supervisor.add(name, processes[name], [*common, *options], env=security.agent_env(name))
    return _Run(spec=spec, scene_path=loaded.path, policy=policy, run_id=run_id, graph_name=graph_name,
                run_dir=run_dir, port=port, endpoint=endpoint, agents=agents, security=security, env=env,
                supervisor=supervisor, router=router, record=record,
                restart_log_from=len(supervisor.budget.log))


def check_log_rotation(env: Mapping[str, str]) -> None:
    """A bad ``CHRONAV_LOG_ROTATE_S`` refused before the run starts, rather than by every process."""
    from dsr.log_rotation import rotate_period_s

    try:
        rotate_period_s(env)
    except ValueError as exc:
        raise LaunchError(str(exc)) from None


def _agent_options(name: str, *, rate: float | None, ros_domain: int | None, robot: str,
                   extra: list[str]) -> list[str]:
    """One agent's ``-o key=value`` arguments: the run's rate, ROS domain and robot, then ``extra``."""
    options = [*(["-o", f"rate={rate}"] if rate is not None and name == "sim_robot" else [])]
    options += ["-o", f"ros_domain={ros_domain}"] if name == ROS_BRIDGE else []
    options += ["-o", "robot=ros"] if robot == "ros" and name in ("sim_robot", ROS_BRIDGE) else []
    for opt in extra:
        options += ["-o", opt]
    return options


def _start_processes(run: _Run, stop: _StopRequest) -> bool:
    """The router, then (once it listens) the connect file and the agents; False if a stop came
    before the router listened, LaunchError if it never did."""
    run.supervisor.start("router")
    if not wait_for_port(run.port, 15, give_up=lambda: stop.requested or not run.router.alive):
        if not stop.requested:
            raise LaunchError(f"the Zenoh router did not listen on {run.endpoint}; see {run.router.log_path}")
        return False
    write_connect_file(run.run_dir, run_id=run.run_id, endpoint=run.endpoint, graph=run.graph_name,
                       security=run.security)
    for name in run.agents:
        run.supervisor.start(name)
    write_pids(run.run_dir, run.supervisor, run.router.pid)
    return True


def _watch_until_over(run: _Run, stop: _StopRequest, watch: ProgressWatch, recorder: Recorder, *,
                      timeout_s: float, on_tick: Callable[[dict[str, object]], None] | None,
                      settle_s: float = 0.0) -> None:
    """Join the graph read-only and, until the run is over, poll the processes, restart hung agents,
    log the graph and hand the status to ``on_tick``; with ``settle_s``, a last status once the
    graph holds no tombstone (``_settled_status``)."""
    from agents.runtime.drawing.dsr_graph import GraphLogger
    from agents.runtime.heartbeat import read_stamp
    from dsr import join
    from dsr.config import ZenohSettings

    supervisor = run.supervisor
    settings = ZenohSettings.from_env({**run.env, "CHRONAV_ZENOH_USER": run.security.reader.user,
                                       "CHRONAV_ZENOH_PASSWORD": run.security.reader.password})
    # Read-only: the launcher only watches; it enforces the agents' write policy too.
    with join(agent="launcher", graph=run.graph_name, settings=settings, read_only=True,
              policy=run.policy) as graph:
        graph_logger = GraphLogger(recorder)
        status: dict[str, Any] = {}
        while True:
            graph.dispatch(timeout=0.1)
            changed = bool(supervisor.poll())
            changed |= _restart_stuck(graph, supervisor, watch, read_stamp)
            if changed:
                write_pids(run.run_dir, supervisor, run.router.pid)
            status = _run_status(graph, supervisor, run)
            run.missions = status["missions"]
            run.problems = status["problems"]
            graph_logger.maybe_log(graph, status.get("now_s"))
            if on_tick is not None:
                on_tick(status)
            if _run_over(run, stop, status, timeout_s):
                break
        if settle_s > 0 and on_tick is not None and not (run.interrupted or run.timed_out):
            status = _settled_status(graph, supervisor, run, settle_s)
            on_tick(status)
        graph_logger.maybe_log(graph, status.get("now_s"), force=True)
        write_final_graph(run.run_dir, graph)


def _settled_status(graph: Any, supervisor: Supervisor, run: _Run, settle_s: float) -> dict[str, Any]:
    """The status once the graph's tombstones are forgotten, or after ``settle_s`` wall seconds.

    Why: the day's last removals (the last mission's intention, people leaving) are remembered until
    every member has acknowledged them, one or two digest rounds (0.5 s each, dsr/anti_entropy.py);
    read at once, a day's end counted 0 to 4 tombstones by chance, which a day-over-day ratio
    read as growth.  Nothing accumulates: each day has a new graph."""
    deadline = time.monotonic() + settle_s
    while graph.tombstones() > 0 and time.monotonic() < deadline:
        graph.dispatch(timeout=0.1)
    return _run_status(graph, supervisor, run)


def _run_status(graph: Any, supervisor: Supervisor, run: _Run) -> dict[str, Any]:
    """What ``on_tick`` gets: the graph's and processes' status and where the run is."""
    status = _status(graph, supervisor, run.started)
    status["run"] = {"run_dir": str(run.run_dir), "endpoint": run.endpoint, "graph": run.graph_name}
    return status


def _run_over(run: _Run, stop: _StopRequest, status: Mapping[str, object], timeout_s: float) -> bool:
    """Whether the watch ends now: a stop, every mission terminal, the clock finished, the timeout
    (noted on ``run``), or a process of chronav's the supervisor gave up on (not an agent plug-in's:
    the run goes on without it, as when it is refused at start)."""
    from agents.world.vocabulary import MissionState

    missions = run.missions
    if stop.requested:
        run.interrupted = True
        return True
    if len(missions) == len(run.spec.missions) and missions and all(
            m.get("state") in MissionState.TERMINAL for m in missions.values()):
        return True
    if status.get("clock_finished"):
        return True
    if time.monotonic() - run.started > timeout_s:
        run.timed_out = True
        return True
    return any(_ends_the_run(name) for name in run.supervisor.given_up() or ())


def _ends_the_run(process: str) -> bool:
    """Whether giving up on ``process`` ends a run: chronav's own agents, the router and the ROS
    bridge do; an outside package's agent plug-in does not."""
    from agents.lib.agent_plugins import package_of
    from agents.lib.registry import OWN_PACKAGE, UnknownExtension

    try:
        return package_of(process) == OWN_PACKAGE
    except UnknownExtension:       # the router, the ROS bridge
        return True


def _finish(run: _Run, recorder: Recorder) -> RunResult:
    """Stop every process, close and merge the recordings, write ``result.json``; the run's result."""
    run.supervisor.stop_all(order=[*reversed(run.agents), "router"])
    recorder.close()
    rrd_path: Path | None = None
    hours: list[dict[str, Any]] = []
    if run.record:
        rrd_path, hours = merge_run_recording(run.run_dir, run.run_id)
    missions = {**scene_missions(run.spec), **run.missions}
    result = RunResult(scene=run.spec.name, run_dir=run.run_dir, rrd_path=rrd_path, missions=missions, hours=hours,
                       events=list(run.supervisor.events),
                       restarts={n: m.restarts for n, m in run.supervisor.processes.items()},
                       wall_s=time.monotonic() - run.started, interrupted=run.interrupted,
                       timed_out=run.timed_out, metrics=run.metrics, scene_path=run.scene_path, error=run.error,
                       problems=dict(run.problems),
                       restart_log=[r.as_json() for r in run.supervisor.budget.log[run.restart_log_from:]])
    _write_result(result)
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


def write_final_graph(run_dir: Path, graph: Any) -> None:
    """``<run>/graph.json``: the DSR graph as the run ended (``chronav dsr dump --json``'s nodes and
    edges), so what the agents wrote, a plug-in agent's nodes among them, can be read after the run.
    A launch writes its watching replica's, which took in only the writes the policy allowed."""
    (run_dir / FINAL_GRAPH).write_text(graph.to_json())


def _write_result(result: RunResult) -> None:
    from tools.live_prediction import live_prediction   # the observer's predictions against people.csv

    (result.run_dir / "result.json").write_text(json.dumps({
        "scene": result.scene, "ok": result.ok, "missions": result.missions, "events": result.events,
        "restarts": result.restarts, "restart_log": result.restart_log, "wall_s": result.wall_s, "rrd": str(result.rrd_path) if result.rrd_path else None,
        "hours": [{**h, "rrd": str(h["rrd"])} for h in result.hours],
        "interrupted": result.interrupted, "timed_out": result.timed_out, "error": result.error,
        "problems": result.problems,
        "scene_path": str(result.scene_path.resolve()) if result.scene_path else None,
        "prediction": live_prediction(result.run_dir)}, indent=2))
    from tools.system.mission_slices import ensure_mission_slices

    ensure_mission_slices(result.run_dir, result.missions)   # missions/<id>.csv, .people.csv, .json


def _status(graph, supervisor: Supervisor, started: float) -> dict[str, Any]:   # JSON-like, as on_tick gets it
    from agents.runtime.heartbeat import read_problem
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
        "dsr": graph.counts(),   # the launcher's replica: nodes, edges, tombstones (long runs, tools/week.py)
        "pids": {name: m.pid for name, m in supervisor.processes.items()},  # fault injection (tools/chaos/command.py)
        # what an agent reports as keeping it from its job (the ROS side unreachable...), for the console
        "problems": {name: p for name in supervisor.processes if name != "router" and (p := read_problem(graph, name))},
        "wall_s": time.monotonic() - started,
    }

"""`chronav launch SCENE` / `chronav demo`: the whole system, one process per agent.

Order matters (see shared notes): the Zenoh router first (agents in client mode fail at once if
no router listens), then the agents; the launcher joins the graph itself only to watch missions,
clock and health.  At the end the per-agent recordings are merged into ONE ``.rrd``.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path

import typer

from tools.supervisor import REPO_ROOT, Supervisor

AGENTS: tuple[str, ...] = ("sim_robot", "object_recognition", "human_observer", "agenda", "social_navigation",
                           "executive")
DEFAULT_SCENE = "icra_usecase"
TERMINAL_STATES = ("done", "failed")


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

    @property
    def ok(self) -> bool:
        return (not self.interrupted and not self.timed_out and bool(self.missions)
                and all(m.get("state") == "done" for m in self.missions.values()))


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def wait_for_port(port: int, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
            if sock.connect_ex(("127.0.0.1", port)) == 0:
                return True
        time.sleep(0.05)
    return False


def rerun_binary() -> Path:
    """The real viewer/CLI binary inside the wheel (the console script is a Python wrapper)."""
    import rerun_cli

    return Path(rerun_cli.__file__).parent / "rerun"


def merge_recordings(parts: list[Path], out: Path) -> Path | None:
    """`rerun rrd optimize` = merge + compaction + footer; parts of killed agents are accepted."""
    if not parts:
        return None
    result = subprocess.run([str(rerun_binary()), "rrd", "optimize", *map(str, parts), "-o", str(out)],
                            capture_output=True, text=True, timeout=300, check=False)
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


def write_connect_file(run_dir: Path, endpoint: str, graph: str) -> None:
    """connect.json: how tools (`chronav agenda --run ...`) join this run while it is live."""
    tmp = run_dir / "connect.json.tmp"
    tmp.write_text(json.dumps({"endpoint": endpoint, "graph": graph, "launcher_pid": os.getpid()}))
    tmp.replace(run_dir / "connect.json")


def run_system(scene: str | Path, *, rate: float | None = None, runs_dir: Path = REPO_ROOT / "recordings",
               timeout_s: float = 900.0, record: bool = True, restart_limit: int = 3,
               agent_options: dict[str, list[str]] | None = None,
               on_tick: Callable[[dict[str, object]], None] | None = None) -> RunResult:
    """Run one scene end to end; return when every mission is done or failed, or on timeout/Ctrl-C."""
    from agents.runtime.recording import Recorder
    from dsr import join
    from dsr.config import ZenohSettings
    from agents.world.write_policy import policy_from_env
    from agents.world.scene_world import load_world
    from agents.runtime.drawing.social_map import log_walls
    from agents.runtime.drawing.layout import blueprint, world_frame
    from agents.runtime.drawing.dsr_graph import GraphLogger

    loaded = load_world(scene)
    spec = loaded.scene
    policy = policy_from_env()  # fail before any process starts if the write policy is broken
    run_id = f"{spec.name}-{datetime.now().strftime('%Y%m%d-%H%M%S')}-{os.getpid()}"
    run_dir = runs_dir / run_id
    run_dir.mkdir(parents=True, exist_ok=True)
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    env = {**os.environ, "CHRONAV_ZENOH_CONNECT": endpoint, "CHRONAV_ZENOH_MODE": "client",
           "CHRONAV_GRAPH": run_id.replace(".", "_"), "CHRONAV_RECORDING_ID": run_id,
           "PYTHONUNBUFFERED": "1", "CHRONAV_EXIT_WITH_PARENT": "1"}
    if not record:
        env["RERUN"] = "off"
    supervisor = Supervisor(run_dir / "logs", env, restart_limit=restart_limit)
    router = supervisor.add("router", "dsr.router", ["--listen", endpoint])
    common = ["--scene", str(loaded.path.resolve()), "--run-dir", str(run_dir), "--recording-id", run_id]
    for name in AGENTS:
        options = [*(["-o", f"rate={rate}"] if rate and name == "sim_robot" else [])]
        for opt in (agent_options or {}).get(name, []):
            options += ["-o", opt]
        supervisor.add(name, f"agents.{name}", [*common, *options])

    started = time.monotonic()
    interrupted = timed_out = False
    previous_sigint = signal.getsignal(signal.SIGINT)
    stop_requested = {"flag": False}

    def on_sigint(_signum: int, _frame: object) -> None:
        stop_requested["flag"] = True

    signal.signal(signal.SIGINT, on_sigint)
    previous_sigterm = signal.signal(signal.SIGTERM, on_sigint)  # stopped by a supervisor: clean up too
    missions: dict[str, dict[str, object]] = {}
    metrics: dict[str, object] = {}
    recorder = Recorder("launcher", run_dir if record else None, run_id)
    recorder.send_blueprint(blueprint())
    world_frame(recorder)
    log_walls(recorder, [[list(p) for p in wall] for wall in spec.walls])
    try:
        supervisor.start("router")
        if not wait_for_port(port, 15):
            raise RuntimeError(f"the Zenoh router did not listen on {endpoint}; see {router.log_path}")
        write_connect_file(run_dir, endpoint, env["CHRONAV_GRAPH"])
        for name in AGENTS:
            supervisor.start(name)
        write_pids(run_dir, supervisor, router.pid)
        settings = ZenohSettings.from_env(env)
        # Read-only: the launcher only watches; it enforces the agents' write policy too.
        with join(agent="launcher", graph=env["CHRONAV_GRAPH"], settings=settings, read_only=True,
                  policy=policy) as graph:
            graph_logger = GraphLogger(recorder)
            while True:
                graph.dispatch(timeout=0.1)
                if supervisor.poll():
                    write_pids(run_dir, supervisor, router.pid)
                status = _status(graph, supervisor, started)
                status["run"] = {"run_dir": str(run_dir), "endpoint": endpoint, "graph": env["CHRONAV_GRAPH"]}
                missions = status["missions"]  # type: ignore[assignment]
                graph_logger.maybe_log(graph, status.get("now_s"))
                if on_tick is not None:
                    on_tick(status)
                if stop_requested["flag"]:
                    interrupted = True
                    break
                if len(missions) == len(spec.missions) and missions and all(
                        m.get("state") in TERMINAL_STATES for m in missions.values()):
                    break
                if status.get("clock_finished"):
                    break
                if time.monotonic() - started > timeout_s:
                    timed_out = True
                    break
                if supervisor.given_up():
                    break
            graph_logger.maybe_log(graph, status.get("now_s"), force=True)
        if record:
            # Metrics of the day (social vs baseline) as scalars in this same recording.
            from tools.report import build_report, log_report

            metrics = build_report(loaded.path, run_dir, missions)
            log_report(recorder, metrics, missions)
    finally:
        signal.signal(signal.SIGINT, previous_sigint)
        signal.signal(signal.SIGTERM, previous_sigterm)
        agents_first = [*reversed(AGENTS), "router"]
        supervisor.stop_all(order=agents_first)
        recorder.close()
    rrd_path = None
    if record:
        rrd_path = merge_recordings(sorted((run_dir / "rrd").glob("*.rrd")), runs_dir / f"{run_id}.rrd")
    result = RunResult(scene=spec.name, run_dir=run_dir, rrd_path=rrd_path, missions=missions,
                       events=list(supervisor.events), restarts={n: m.restarts for n, m in supervisor.processes.items()},
                       wall_s=time.monotonic() - started, interrupted=interrupted, timed_out=timed_out,
                       metrics=metrics, scene_path=loaded.path)
    (run_dir / "result.json").write_text(json.dumps({
        "scene": result.scene, "ok": result.ok, "missions": result.missions, "events": result.events,
        "restarts": result.restarts, "wall_s": result.wall_s, "rrd": str(rrd_path) if rrd_path else None,
        "interrupted": interrupted, "timed_out": timed_out}, indent=2))
    return result


def _status(graph, supervisor: Supervisor, started: float) -> dict[str, object]:  # noqa: ANN001
    clock = graph.get_node_by_name("clock")
    missions = {}
    for node in graph.nodes_of_type("mission"):
        missions[str(node.attrs.get("mission_id", node.name))] = dict(node.attrs)
    return {
        "now_s": None if clock is None else float(clock.attrs.get("now_s", 0.0)),
        "clock_mode": None if clock is None else clock.attrs.get("mode"),
        "clock_finished": bool(clock is not None and clock.attrs.get("finished")),
        "missions": missions,
        "agents": {name: ("up" if m.alive else "down", m.restarts) for name, m in supervisor.processes.items()},
        "pids": {name: m.pid for name, m in supervisor.processes.items()},  # fault injection (tools/chaos.py)
        "wall_s": time.monotonic() - started,
    }


def register(app: typer.Typer) -> None:
    @app.command("launch")
    def launch(scene: str = typer.Argument(..., help="scene file or name in scenes/"),
               rate: float = typer.Option(None, help="sim seconds per wall second (default: the scene's)"),
               timeout: float = typer.Option(900.0, help="wall-clock limit in seconds"),
               no_record: bool = typer.Option(False, "--no-record", help="do not write a Rerun recording"),
               restart_limit: int = typer.Option(3, help="restarts allowed per agent"),
               as_json: bool = typer.Option(False, "--json", help="print the result as one JSON object")) -> None:
        """Run every agent as its own process on SCENE until the day's missions are done."""
        from tools.console import run_with_progress

        code = run_with_progress(scene, rate=rate, timeout_s=timeout, record=not no_record,
                                 restart_limit=restart_limit, as_json=as_json, with_report=False)
        raise typer.Exit(code)

    @app.command("demo")
    def demo(scene: str = typer.Argument(DEFAULT_SCENE, help="scene file or name"),
             as_json: bool = typer.Option(False, "--json")) -> None:
        """The main job: launch the default scene, then print the social vs non-social metrics table."""
        from tools.console import run_with_progress

        raise typer.Exit(run_with_progress(scene, rate=None, timeout_s=600, record=True, restart_limit=3,
                                           as_json=as_json, with_report=True))

"""`chronav ros bridge SCENE [--run RUN]`: the ROS 2 bridge alone, against a system already running.

Why a command (beside `chronav launch --ros`): a researcher often starts RViz or a robot after the
run; the bridge then joins the run's DSR as its own agent, with the identity every run provisions
for it (``<run>/secrets/ros_bridge.password``, readable by the run's owner only), and serves the
ROS side until Ctrl-C.  Against a system started by hand (no run directory) it joins without
credentials, as the agents of such a system do.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import typer

PROBE_TIMEOUT_S = 5.0

ros_app = typer.Typer(help="chronav and ROS 2 (docs/ros2.md).", no_args_is_help=True)


def register(app: typer.Typer) -> None:
    app.add_typer(ros_app, name="ros")


@ros_app.command("bridge")
def bridge(scene: str = typer.Argument(..., help="the running system's scene file or name"),
           run: str = typer.Option(None, "--run", help="'latest', a run directory or a run id (default: your "
                                                       "newest live run)"),
           ros_domain: int = typer.Option(None, "--ros-domain", min=0, max=232,
                                          help="ROS_DOMAIN_ID (default: $ROS_DOMAIN_ID or 0)"),
           ros_endpoint: str = typer.Option(None, "--ros-endpoint", help="the ROS side's Zenoh router "
                                            "(default: $CHRONAV_ROS_ENDPOINT or tcp/127.0.0.1:7447)"),
           ros_config: Path = typer.Option(None, "--ros-config", help="YAML: topics, frames, QoS (docs/ros2.md)")
           ) -> None:
    """Publish a running system's map, social costmap, people, plan, tf, odom, scan and agenda to ROS 2;
    /goal_pose becomes a pose mission.  Runs until Ctrl-C."""
    from agents.ros_bridge.agent import RosBridgeAgent
    from agents.runtime.base import run_agent
    from tools.system.connection import ConnectionProblem, open_replica, resolve_target

    try:
        target = resolve_target(None, None, run, role="reader")
        # Can the system be reached?  Asked as the run's reader first, so that "no run" is one line
        # saying what to do (as `chronav agenda` and `dsr dump` say it), not the agent's traceback.
        # (A run whose agents have not joined yet is fine: the bridge waits for its world.)
        with open_replica(target, agent=f"ros_bridge_probe-{os.getpid()}", read_only=True,
                          timeout_s=PROBE_TIMEOUT_S):
            pass
    except ConnectionProblem as exc:
        sys.stderr.write(f"chronav ros bridge: {exc}\n")
        raise typer.Exit(2) from None
    env = {"CHRONAV_ZENOH_CONNECT": ",".join(target.connect), "CHRONAV_ZENOH_MODE": "client",
           "CHRONAV_GRAPH": target.graph}
    if target.run_dir is not None:
        password = target.run_dir / "secrets" / "ros_bridge.password"
        if not password.exists():
            sys.stderr.write(f"error: run {target.run_dir} has no identity for the ROS bridge ({password}); "
                             "it was started by an older chronav: restart it, or use `chronav launch --ros`\n")
            raise typer.Exit(2)
        env.update(CHRONAV_ZENOH_USER="ros_bridge", CHRONAV_ZENOH_PASSWORD_FILE=str(password))
    for key in [k for k in os.environ if k.startswith("CHRONAV_ZENOH_")]:
        os.environ.pop(key)
    os.environ.update(env)
    argv = ["--scene", scene, "--name", "ros_bridge", "--graph", target.graph]
    for key, value in (("ros_domain", ros_domain), ("ros_endpoint", ros_endpoint), ("ros_config", ros_config)):
        if value is not None:
            argv += ["-o", f"{key}={value}"]
    if target.run_dir is not None:
        argv += ["--run-dir", str(target.run_dir)]
    sys.stderr.write(f"ROS 2 bridge joining {target.describe()}\n")
    raise typer.Exit(run_agent(RosBridgeAgent, argv))


@ros_app.command("stats")
def stats(ros_domain: int = typer.Option(None, "--ros-domain", min=0, max=232,
                                         help="ROS_DOMAIN_ID (default: $ROS_DOMAIN_ID or 0)"),
          ros_endpoint: str = typer.Option(None, "--ros-endpoint", help="the ROS side's Zenoh router "
                                           "(default: $CHRONAV_ROS_ENDPOINT or tcp/127.0.0.1:7447)"),
          ros_config: Path = typer.Option(None, "--ros-config", help="YAML: topics, frames, QoS (docs/ros2.md)"),
          timeout: float = typer.Option(5.0, "--timeout", min=0.1, max=600.0,
                                        help="seconds to wait for the bridge's /diagnostics"),
          run: str = typer.Option(None, "--run", help="a run directory or id: the counts that run kept "
                                                      "(<run>/ros_received.json; no ROS network needed)"),
          as_json: bool = typer.Option(False, "--json", help="print one JSON object")) -> None:
    """What the running bridge received from ROS 2 and refused, per topic and reason (from its
    /diagnostics, published once a second; with --run, from what a run kept)."""
    import json

    from agents.ros_bridge.config import BridgeConfigError, config_from_options
    from tools.ros.export_mcap import ExportError, find_run
    from tools.ros.stats import NoDiagnostics, read_stats, stats_of_run
    from tools.system.runs import runs_dir

    options = {k: str(v) for k, v in (("ros_domain", ros_domain), ("ros_endpoint", ros_endpoint),
                                       ("ros_config", ros_config)) if v is not None}
    try:
        if run is not None:
            document = stats_of_run(find_run(run, runs_dir()))
        else:
            document = read_stats(config_from_options(options), timeout)
    except (BridgeConfigError, NoDiagnostics, ExportError) as exc:
        sys.stderr.write(f"error: {exc}\n")
        raise typer.Exit(1) from None
    if as_json:
        print(json.dumps(document))
        return
    from rich.console import Console
    from rich.table import Table

    where = f"run {document['run']}" if "run" in document else f"domain {document['domain']}"
    table = Table(title=f"ROS 2 node /{document['node']} ({where}): received")
    for column in ("topic", "taken", "refused", "refused (by reason)"):
        table.add_column(column, overflow="fold")
    for topic, row in sorted(document["topics"].items()):
        reasons = ", ".join(f"{k}={v}" for k, v in sorted(row["reasons"].items()))
        table.add_row(topic, str(row["taken"]), str(row["refused"]), reasons or "0")
    Console().print(table)

"""``chronav launch`` and ``chronav demo``: the command-line face of tools/launch.py.

Why apart from the launcher: the commands show progress through tools/system/console.py, which
runs the launcher (or the in-process runner); with the commands inside tools/launch.py the
launcher and its console imported each other.  Now: launch_cli -> console -> launch.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import typer

from tools.walker_models import model_options
from tools.launch import (DEFAULT_HANG_TIMEOUT_S, DEFAULT_SCENE, DEFAULT_STARTUP_TIMEOUT_S, LaunchError, check_log_rotation,
                          check_rate, check_timeout)


def _option_check(check: Callable[..., Any], option: str) -> Callable[[Any], Any]:
    """A typer callback refusing a bad value at once, in the check's words (exit 2)."""
    def callback(value: Any) -> Any:
        if value is None:
            return value
        try:
            return check(value, option)
        except LaunchError as exc:
            raise typer.BadParameter(str(exc).removeprefix(f"{option} ")) from None
    return callback


def check_controller(name: str, option: str) -> str:
    """``name`` if an installed controller loads, else a usage error naming the known ones (and
    their packages) or the plug-in, its package and why it is refused."""
    from agents.lib.control.controllers import controller
    from agents.lib.control.protocol import RobotLimits
    from agents.lib.registry import RefusedExtension, UnknownExtension

    try:   # built once for a generic robot: its factory and protocol are checked before anything starts
        controller(name, RobotLimits(radius_m=0.3, max_speed_mps=0.6, max_angular_speed_radps=1.2))
    except (UnknownExtension, RefusedExtension) as exc:
        raise typer.BadParameter(str(exc), param_hint=option) from None
    return name


def _spans_days(scene: str) -> bool:
    """Whether SCENE's clock spans more than one day (its days then run one after the other)."""
    from tools.week import scene_days

    return scene_days(scene) > 1


def register(app: typer.Typer) -> None:
    @app.command("launch")
    def launch(scene: str = typer.Argument(..., help="scene file or name in scenes/"),
               rate: float = typer.Option(None, help="sim seconds per wall second, > 0 (default: the scene's)",
                                          callback=_option_check(check_rate, "--rate")),
               timeout: float = typer.Option(900.0, help="wall-clock limit in seconds, > 0",
                                             callback=_option_check(check_timeout, "--timeout")),
               hang_timeout: float = typer.Option(DEFAULT_HANG_TIMEOUT_S, help="restart an agent whose heartbeat "
                                                  "stops for this many wall seconds",
                                                  callback=_option_check(check_timeout, "--hang-timeout")),
               startup_timeout: float = typer.Option(DEFAULT_STARTUP_TIMEOUT_S, help="restart an agent that writes "
                                                     "no first heartbeat within this many wall seconds of its start",
                                                     callback=_option_check(check_timeout, "--startup-timeout")),
               no_record: bool = typer.Option(False, "--no-record", help="do not write a Rerun recording"),
               restart_limit: int = typer.Option(3, min=0, help="restarts allowed per agent"),
               ros: bool = typer.Option(False, "--ros", help="also start the ROS 2 bridge (topics over rmw_zenoh; "
                                        "router endpoint from CHRONAV_ROS_ENDPOINT, default tcp/127.0.0.1:7447)"),
               ros_domain: int = typer.Option(None, "--ros-domain", min=0, max=232,
                                              help="ROS_DOMAIN_ID of --ros (default: $ROS_DOMAIN_ID or 0)"),
               robot: str = typer.Option("sim", "--robot", help="sim: the simulated robot; ros: a ROS 2 robot "
                                         "(its /odom and /scan in, /cmd_vel out; starts the ROS 2 bridge itself, --ros not needed)"),
               in_process: bool = typer.Option(False, "--in-process",
                                               help="every agent in this process, stepped in lockstep on one graph "
                                                    "(no router, no restarts; as fast as the machine allows)"),
               controller: str = typer.Option(None, "--controller",
                                              help="the robot's local controller, a registered one (`chronav "
                                                   "plugins` lists them; default elastic_band)"),
               model: Path | None = typer.Option(None, "--model", help="walker model file for the human observer "
                                                                        "(chronav predict train; default: the shipped one)"),
               days: int = typer.Option(None, "--days", min=1, help="run this many days from the scene's date "
                                        "(default: its clock.days); one recording per day (docs/long_runs.md)"),
               keep_days: int = typer.Option(None, "--keep-days", min=1, help="of a run of days, keep the "
                                             "recordings and logs of the newest K days only"),
               as_json: bool = typer.Option(False, "--json", help="print the result as one JSON object")) -> None:
        """Run every agent as its own process on SCENE until the day's missions are done.

        With --in-process the same agents run in this one process, stepped in lockstep (reproducible
        run for run). The run goes to ./recordings/<run id>/ (or $CHRONAV_RUNS/<run id>/)."""
        from tools.system.console import run_with_progress

        domain = None
        if in_process and (ros or ros_domain is not None or robot != "sim"):
            raise typer.BadParameter("--in-process runs every agent on one graph without Zenoh, so the ROS 2 "
                                     "bridge cannot join it: drop --in-process to use --ros or --robot ros")
        if ros or ros_domain is not None or robot == "ros":
            try:
                domain = ros_domain if ros_domain is not None else int(os.environ.get("ROS_DOMAIN_ID") or 0)
            except ValueError:
                raise typer.BadParameter(f"ROS_DOMAIN_ID={os.environ.get('ROS_DOMAIN_ID')!r} is not a number; "
                                         "set it to 0-232 or give --ros-domain N") from None
        if controller is not None:
            check_controller(controller, "--controller")
        if not in_process:
            try:   # read by every process of the run: refused once, here, before any starts
                check_log_rotation(os.environ)
            except LaunchError as exc:
                raise typer.BadParameter(str(exc)) from None
        if days is not None or keep_days is not None or _spans_days(scene):
            from tools.system.week_console import run_days_with_progress

            chosen = dict(model_options(model) or {})
            if controller is not None:
                chosen["social_navigation"] = [f"controller={controller}"]
            supervision = {} if in_process else {"restart_limit": restart_limit, "hang_timeout_s": hang_timeout,
                                                 "startup_timeout_s": startup_timeout, "ros_domain": domain,
                                                 "robot": robot}
            raise typer.Exit(run_days_with_progress(scene, days=days, keep_days=keep_days, in_process=in_process,
                                                    as_json=as_json, rate=rate, timeout_s=timeout,
                                                    record=not no_record, agent_options=chosen or None,
                                                    **supervision))
        code = run_with_progress(scene, rate=rate, timeout_s=timeout, record=not no_record,
                                 restart_limit=restart_limit, as_json=as_json, with_report=False,
                                 hang_timeout_s=hang_timeout, startup_timeout_s=startup_timeout, ros_domain=domain,
                                 robot=robot, in_process=in_process, controller=controller,
                                 agent_options=model_options(model))
        raise typer.Exit(code)

    @app.command("demo")
    def demo(scene: str = typer.Argument(DEFAULT_SCENE, help="scene file or name"),
             as_json: bool = typer.Option(False, "--json")) -> None:
        """The main job: launch the default scene, then print the social vs non-social metrics table."""
        from tools.system.console import run_with_progress

        raise typer.Exit(run_with_progress(scene, rate=None, timeout_s=600, record=True, restart_limit=3,
                                           as_json=as_json, with_report=True))

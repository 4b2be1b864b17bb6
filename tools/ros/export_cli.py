"""`chronav export RUN --format mcap --out FILE.mcap`: a finished run for ROS 2 tools (tools/ros/export_mcap.py)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import typer

FORMATS = ("mcap",)


def register(app: typer.Typer) -> None:
    @app.command("export")
    def export(run: str = typer.Argument(..., help="a finished run: 'latest' (your newest finished run), its "
                                                   "directory, or its id under ./recordings ($CHRONAV_RUNS)"),
               fmt: str = typer.Option("mcap", "--format", help="mcap: a rosbag2 MCAP file (ros2 bag, Foxglove)"),
               out: Path = typer.Option(..., "--out", help="the file to write, e.g. run.mcap"),
               scene: str = typer.Option(None, "--scene", help="the run's scene file (default: the one the run "
                                                               "names in result.json)"),
               as_json: bool = typer.Option(False, "--json", help="print a summary as one JSON object")) -> None:
        """Write a finished run's topics (odom, tf, people, clock, map, social costmap, agenda, plan) as a ROS 2 bag,
        stamped in the scene's clock."""
        from scenes.yamlio import SourceError
        from tools.ros.export_mcap import ExportError, export_mcap, find_run
        from tools.system.runs import runs_dir

        if fmt not in FORMATS:
            sys.stderr.write(f"error: --format {fmt!r}: the formats are {', '.join(FORMATS)}\n")
            raise typer.Exit(2)
        try:
            run_dir = find_run(run, runs_dir())
            summary = {"run_dir": str(run_dir), **export_mcap(run_dir, out, scene)}
        except (ExportError, SourceError) as exc:
            sys.stderr.write(f"error: {exc}\n")
            raise typer.Exit(1) from None
        if as_json:
            print(json.dumps(summary))
        else:
            total = sum(summary["messages"].values())
            topics = ", ".join(f"{k} {v}" for k, v in sorted(summary["messages"].items()))
            print(f"wrote {out} from run {run_dir.name}: {total} messages ({topics})")

"""Agent process configuration, from command-line flags and environment.

Why pydantic and a plain object: py_trees-style, an agent's ``__init__`` takes only this config
and does no I/O, so agents can be built and unit-tested offline; the runner owns the middleware.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field


class AgentConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")

    name: str = Field(description="agent instance name, also its DSR writer id")
    scene: Path = Field(description="scene YAML the run is about")
    graph: str = Field("chronav", description="DSR graph name (Zenoh key space chronav/<graph>/...)")
    period_s: float = Field(0.02, gt=0, description="wall-clock loop period")
    run_dir: Path | None = Field(None, description="where logs, per-agent .rrd and CSV outputs go")
    recording_id: str | None = Field(None, description="shared Rerun recording id of the run")
    options: dict[str, str] = Field(default_factory=dict, description="agent-specific key=value options")

    def option(self, key: str, default: str) -> str:
        return self.options.get(key, default)


def parse_agent_args(default_name: str, argv: list[str] | None = None) -> AgentConfig:
    """The flags every `python -m agents.<name>` accepts (the launcher passes the same ones)."""
    parser = argparse.ArgumentParser(prog=f"python -m agents.{default_name}")
    parser.add_argument("--scene", required=True, type=Path)
    parser.add_argument("--name", default=default_name)
    parser.add_argument("--graph", default=os.environ.get("CHRONAV_GRAPH", "chronav"))
    parser.add_argument("--period", type=float, default=0.02, help="loop period in wall seconds")
    parser.add_argument("--run-dir", type=Path, default=None)
    parser.add_argument("--recording-id", default=os.environ.get("CHRONAV_RECORDING_ID"))
    parser.add_argument("--option", "-o", action="append", default=[], metavar="KEY=VALUE")
    args = parser.parse_args(argv)
    options: dict[str, str] = {}
    for item in args.option:
        key, sep, value = item.partition("=")
        if not sep:
            parser.error(f"--option expects KEY=VALUE, got {item!r}")
        options[key] = value
    return AgentConfig(name=args.name, scene=args.scene, graph=args.graph, period_s=args.period,
                       run_dir=args.run_dir, recording_id=args.recording_id, options=options)

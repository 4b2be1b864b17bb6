"""Helpers for the fault and trust tests: scripted replicas, rates, convergence checks."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from tests.integration.dsr_support import read_status
from tests.support import ProcessGroup

SCRIPT_MODULE = "tests.integration.replica_script"


def spawn_script(procs: ProcessGroup, log_dir: Path, agent: str, *args: str,
                 connect: str | None = None, script: list[dict[str, Any]] | None = None,
                 env: dict[str, str] | None = None, prefix: list[str] | None = None,
                 tag: str = "") -> tuple[Any, Path]:
    """Start `python -m tests.integration.replica_script` (optionally behind `prefix`, e.g. a
    network-namespace exec); returns (process, status path)."""
    name = f"{agent}{tag}"
    status = log_dir / f"{name}.json"
    status.unlink(missing_ok=True)
    argv = ["-m", SCRIPT_MODULE, "--agent", agent, "--status", str(status), *args]
    if connect:
        argv += ["--connect", connect]
    if script:
        argv += ["--script", json.dumps(script)]
    proc = procs.spawn([*(prefix or []), *argv], env=env, log_path=log_dir / f"{name}.log")
    return proc, status


def status_of(path: Path) -> dict[str, Any]:
    return read_status(path) or {}


def rate(history: list[list[float]], start: float, end: float, column: int = 1) -> float:
    """Events per second of history column (1 = acked writes, 2 = deltas received) over a
    wall-clock window."""
    points = [p for p in history if start <= p[0] <= end]
    if len(points) < 2 or points[-1][0] <= points[0][0]:
        return 0.0
    return (points[-1][column] - points[0][column]) / (points[-1][0] - points[0][0])


def holds_all_writes(status: dict[str, Any], acked: dict[str, int]) -> bool:
    """The replica holds every acknowledged monotonic write of every writer."""
    counters = status.get("counters") or {}
    names = set(status.get("names") or ())
    for writer, count in acked.items():
        if count <= 0:
            continue
        counter = counters.get(f"{writer}-counter")
        if counter is None or counter < count - 1:
            return False
        if any(f"{writer}-{k}" not in names for k in range(count)):
            return False
    return True

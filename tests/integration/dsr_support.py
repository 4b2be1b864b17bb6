"""Helpers for DSR multi-process tests: a router process and scripted replica workers."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from tests.support import ProcessGroup, free_port, wait_until
from tools.ports import port_open


def start_router(procs: ProcessGroup, log_dir: Path, port: int | None = None) -> tuple[str, Any]:
    port = port or free_port()
    proc = procs.spawn(["-m", "dsr.router", "--listen", f"tcp/127.0.0.1:{port}"],
                       log_path=log_dir / f"router-{port}.log")
    wait_until(lambda: port_open(port) or proc.poll() is not None, 10, message="router port")
    assert proc.poll() is None, (log_dir / f"router-{port}.log").read_text()
    return f"tcp/127.0.0.1:{port}", proc


def spawn_worker(procs: ProcessGroup, endpoint: str, log_dir: Path, agent: str,
                 *args: str) -> tuple[Any, Path]:
    status = log_dir / f"{agent}.json"
    status.unlink(missing_ok=True)
    proc = procs.spawn(["-m", "tests.integration.replica_worker", "--connect", endpoint,
                        "--agent", agent,
                        "--status", str(status), *args], log_path=log_dir / f"{agent}.log")
    return proc, status


def read_status(path: Path) -> dict[str, Any] | None:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def converged(paths: list[Path]) -> bool:
    statuses = [read_status(p) for p in paths]
    if any(s is None or not s["done"] for s in statuses):
        return False
    return len({s["digest"] for s in statuses}) == 1

"""Shared test helpers: free ports and polling waits (defined once in tools/ports.py, shared with
the tools), process groups that are always cleaned up, and a stand-in for a received Zenoh sample.

Why: multi-process tests must never use fixed ports or fixed sleeps (flaky on a 2-core CI box),
and every spawned process must die even when an assertion fails mid-test.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from tools.ports import free_port, poll, port_open

__all__ = ["REPO_ROOT", "FakeSample", "ProcessGroup", "free_port", "port_open", "process_group", "recording_entities",
           "wait_until"]

REPO_ROOT = Path(__file__).resolve().parents[1]


@dataclass
class FakeSample:
    """What a replica's receiver reads of a Zenoh sample (`key_expr`, `payload.to_bytes()`),
    for tests that feed a stand-in Zenoh channel (tests/unit/test_dsr_receive_on_dispatch.py)."""

    key_expr: str
    data: bytes

    @property
    def payload(self) -> FakeSample:
        return self

    def to_bytes(self) -> bytes:
        return self.data


def wait_until(predicate: Callable[[], bool], timeout: float, interval: float = 0.02,
               message: str = "condition") -> None:
    """Poll ``predicate`` until it is true (tools/ports.poll); raise AssertionError naming
    ``message`` on timeout."""
    if not poll(predicate, timeout, interval_s=interval):
        raise AssertionError(f"timed out after {timeout:.1f} s waiting for {message}")


class ProcessGroup:
    """Starts Python subprocesses in their own process groups and kills them all on exit."""

    def __init__(self) -> None:
        self.procs: list[subprocess.Popen[bytes]] = []

    def spawn(self, args: Sequence[str], env: dict[str, str] | None = None,
              log_path: Path | None = None, cwd: Path | None = None) -> subprocess.Popen[bytes]:
        """Run ``python args...`` from the repo root (or ``cwd``, with the repo on PYTHONPATH);
        output goes to ``log_path`` (or is discarded)."""
        full_env = dict(os.environ)
        full_env.setdefault("RERUN", "off")
        full_env.update(env or {})
        if cwd is not None:
            full_env["PYTHONPATH"] = os.pathsep.join(p for p in (str(REPO_ROOT), full_env.get("PYTHONPATH")) if p)
        out = open(log_path, "wb") if log_path else subprocess.DEVNULL  # noqa: SIM115
        proc = subprocess.Popen([sys.executable, *args], cwd=cwd or REPO_ROOT, env=full_env,
                                stdout=out, stderr=subprocess.STDOUT, start_new_session=True)
        self.procs.append(proc)
        return proc

    def kill(self, proc: subprocess.Popen[bytes], sig: int = signal.SIGKILL) -> None:
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            pass
        if sig == signal.SIGKILL:
            proc.wait(timeout=10)

    def close(self) -> None:
        for proc in self.procs:
            if proc.poll() is None:
                try:
                    os.killpg(proc.pid, signal.SIGTERM)
                except ProcessLookupError:
                    continue
        deadline = time.monotonic() + 5
        for proc in self.procs:
            remaining = max(0.1, deadline - time.monotonic())
            try:
                proc.wait(timeout=remaining)
            except subprocess.TimeoutExpired:
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                proc.wait(timeout=10)


@contextmanager
def process_group() -> Iterator[ProcessGroup]:
    group = ProcessGroup()
    try:
        yield group
    finally:
        group.close()


def rrd_print(recording: Path) -> str:
    """`rerun rrd print` of a recording (footer or not): a line per chunk, ``Chunk(...) ... - /entity - ...``."""
    from tools.launch import rerun_binary

    return subprocess.run([str(rerun_binary()), "rrd", "print", str(recording)], capture_output=True, text=True,
                          timeout=60, check=True).stdout


def recording_entities(recording: Path) -> set[str]:
    """The entity paths of a Rerun recording, as `rerun rrd print` lists its chunks (footer or not)."""
    return {part.split()[0] for part in rrd_print(recording).split(" - /")[1:]}

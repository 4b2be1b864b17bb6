"""An agent whose stop hangs writes every thread's stack to its log before the launcher's SIGKILL.

Why: a fault-test run lost an agent's recording footer because the agent hung while stopping
and was killed at 8 s without a trace of where it hung.  The test plays the launcher: it reads the
agent's stderr until the stacks are there, then SIGKILLs it (no fixed wait for the hang).
"""

from __future__ import annotations

import subprocess
import sys
import time

from tests.support import REPO_ROOT

SCRIPT = """
import os, signal, time
from agents.runtime.base import configure_logging, stop_on_signals
configure_logging("stuck_agent")
stop = stop_on_signals("stuck_agent", trace_after_s=0.2)
os.kill(os.getpid(), signal.SIGTERM)
assert stop.wait(5.0)
def hang_in_teardown():
    time.sleep(30.0)
hang_in_teardown()
"""


def test_a_hanging_stop_dumps_every_threads_stack() -> None:
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT], cwd=REPO_ROOT, stderr=subprocess.PIPE, text=True)
    lines: list[str] = []
    deadline = time.monotonic() + 30
    try:
        assert proc.stderr is not None
        while time.monotonic() < deadline:
            line = proc.stderr.readline()
            if not line:                          # it exited: no hang, or it failed before
                break
            lines.append(line)
            if "hang_in_teardown" in line:        # the stacks reached the log while it hung
                break
    finally:
        proc.kill()
        proc.wait(timeout=10)
    stderr = "".join(lines)
    assert "stuck_agent received signal 15, stopping" in stderr, stderr
    assert "most recent call first" in stderr, stderr
    assert "hang_in_teardown" in stderr, stderr

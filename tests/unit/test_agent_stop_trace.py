"""An agent whose stop hangs writes every thread's stack to its log before the launcher's SIGKILL.

Why: a fault-test run lost an agent's recording footer because the agent hung while stopping
and was killed at 8 s without a trace of where it hung."""

from __future__ import annotations

import subprocess
import sys

from tests.support import REPO_ROOT

SCRIPT = """
import os, signal, time
from agents.runtime.base import configure_logging, stop_on_signals
configure_logging("stuck_agent")
stop = stop_on_signals("stuck_agent", trace_after_s=0.3)
os.kill(os.getpid(), signal.SIGTERM)
assert stop.wait(5.0)
def hang_in_teardown():
    time.sleep(2.0)
hang_in_teardown()
"""


def test_a_hanging_stop_dumps_every_threads_stack() -> None:
    result = subprocess.run([sys.executable, "-c", SCRIPT], cwd=REPO_ROOT, capture_output=True,
                            text=True, timeout=30)
    assert result.returncode == 0, result.stderr
    assert "stuck_agent received signal 15, stopping" in result.stderr
    assert "most recent call first" in result.stderr
    assert "hang_in_teardown" in result.stderr, result.stderr

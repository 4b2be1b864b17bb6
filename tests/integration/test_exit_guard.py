"""The end of a `chronav` process with a daemon thread in a Zenoh call (agents/runtime/exit_guard.py).

Without the guard, a daemon thread returning from a Zenoh `get` while the interpreter finalises
aborts the process ("FATAL: exception not rethrown", SIGABRT: the second test failed so in 4 runs
out of 4 without `main()`'s guard).  Each child runs a Zenoh router and a client session in
itself, a daemon thread querying in a loop, then `tools.cli.main()` (`chronav --help`) as the
console script does."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.support import REPO_ROOT
from tools.ports import free_port

pytestmark = pytest.mark.slow

CHILD = """
import sys, threading, zenoh
port, close_first, marker = int(sys.argv[1]), sys.argv[2] == "close", sys.argv[3]
def config(mode):
    c = zenoh.Config()
    c.insert_json5("mode", f'"{mode}"')
    c.insert_json5("listen/endpoints" if mode == "router" else "connect/endpoints", f'["tcp/127.0.0.1:{port}"]')
    c.insert_json5("scouting/multicast/enabled", "false")
    return c
router = zenoh.open(config("router"))
session = zenoh.open(config("client"))
def query():
    try:
        while True:
            list(session.get("nobody/**", timeout=0.3))
    except zenoh.ZError:          # the session closed: the thread ends
        open(marker, "w").write("ended")
threading.Thread(target=query, name="querier", daemon=True).start()
if close_first:                   # what the commands do: close what they opened
    session.close()
import agents.runtime.exit_guard as guard
guard.GRACE_S = 1.0
from tools.cli import main
sys.argv = ["chronav", "--help"]
main()
"""


def _run(tmp_path: Path, mode: str) -> tuple[subprocess.CompletedProcess[str], Path]:
    marker = tmp_path / f"{mode}.ended"
    proc = subprocess.run([sys.executable, "-c", CHILD, str(free_port()), mode, str(marker)], cwd=REPO_ROOT,
                          capture_output=True, text=True, timeout=120)
    return proc, marker


def test_a_thread_of_a_closed_session_is_waited_for(tmp_path):
    proc, marker = _run(tmp_path, "close")
    assert proc.returncode == 0 and "FATAL" not in proc.stderr, proc.stderr
    assert "still running" not in proc.stderr
    assert marker.read_text() == "ended"      # it ran to its end: not cut off by finalisation


def test_a_thread_still_in_zenoh_ends_the_process_with_the_commands_code(tmp_path):
    proc, marker = _run(tmp_path, "open")
    assert proc.returncode == 0 and "FATAL" not in proc.stderr, proc.stderr
    assert "thread 'querier' still running 1 s after the command ended" in proc.stderr
    assert "Usage" in proc.stdout and not marker.exists()

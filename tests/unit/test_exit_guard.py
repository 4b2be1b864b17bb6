"""agents/runtime/exit_guard.py: a `chronav` process waits for its daemon threads before the
interpreter finalises, and ends with its own exit code when one never stops.  The real case
(a thread in a Zenoh call at exit) is tests/integration/test_exit_guard.py."""

from __future__ import annotations

import subprocess
import sys
import threading

from tests.support import REPO_ROOT
from agents.runtime import exit_guard


def _daemon(target) -> threading.Thread:
    thread = threading.Thread(target=target, name="guard-test", daemon=True)
    thread.start()
    return thread


def test_settle_waits_for_a_daemon_thread_that_ends():
    release = threading.Event()
    ended = []
    thread = _daemon(lambda: (release.wait(5), ended.append(True)))
    threading.Timer(0.2, release.set).start()
    assert thread not in exit_guard.settle(5.0)
    assert ended == [True]


def test_settle_names_a_daemon_thread_still_running_after_the_grace():
    release = threading.Event()
    thread = _daemon(lambda: release.wait(10))
    try:
        assert thread in exit_guard.settle(0.1)
    finally:
        release.set()
        thread.join(5)


def test_exit_codes_as_sys_exit_gives_them():
    assert [exit_guard.exit_code_of(c) for c in (None, 0, 3, "bad input")] == [0, 0, 3, 1]


def test_a_thread_that_never_stops_ends_the_process_with_the_commands_code():
    script = ("import threading, sys\n"
              "from agents.runtime.exit_guard import leave\n"
              "threading.Thread(target=threading.Event().wait, name='stuck', daemon=True).start()\n"
              "try:\n"
              "    raise SystemExit(3)\n"
              "finally:\n"
              "    leave(3, grace_s=0.2)\n"
              "    print('not reached')\n")
    proc = subprocess.run([sys.executable, "-c", script], cwd=REPO_ROOT, capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 3
    assert "thread 'stuck' still running 0.2 s after the command ended" in proc.stderr
    assert "not reached" not in proc.stdout

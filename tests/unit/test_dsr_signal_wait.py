"""dispatch(timeout=...) waits at most its timeout even when signals interrupt it (CPython's
SimpleQueue.get(timeout=) may wait forever after a signal: agents hung on SIGTERM), and wakes
as soon as another thread posts."""

from __future__ import annotations

import subprocess
import sys
import threading
import time

from dsr.signals import SignalHub
from tests.support import REPO_ROOT

STORM = r"""
import os, signal, sys, threading, time
from dsr.signals import SignalHub
hub = SignalHub()
signal.signal(signal.SIGUSR1, lambda s, f: None)
done = False
def storm():
    while not done:
        time.sleep(0.003)
        os.kill(os.getpid(), signal.SIGUSR1)
threading.Thread(target=storm, daemon=True).start()
worst, end = 0.0, time.monotonic() + 2.0
while time.monotonic() < end:
    t = time.monotonic()
    hub.dispatch(timeout=0.02)
    worst = max(worst, time.monotonic() - t)
done = True
print(worst)
"""


def test_a_signal_storm_never_stretches_a_wait() -> None:
    result = subprocess.run([sys.executable, "-c", STORM], cwd=REPO_ROOT, capture_output=True,
                            text=True, timeout=20)
    assert result.returncode == 0, result.stderr
    assert float(result.stdout) < 0.5


def test_a_post_from_another_thread_wakes_the_wait_and_a_wait_times_out() -> None:
    hub = SignalHub()
    got: list[int] = []
    hub.connect("node_deleted", got.append)
    start = time.monotonic()
    assert hub.dispatch(timeout=0.1) == 0 and 0.09 <= time.monotonic() - start < 1.0
    threading.Timer(0.05, lambda: hub.post([("node_deleted", (7,))])).start()
    start = time.monotonic()
    assert hub.dispatch(timeout=5.0) == 1 and got == [7] and time.monotonic() - start < 2.0
    hub.post([("node_deleted", (8,))])
    hub.post([("node_deleted", (9,))])
    assert hub.dispatch(timeout=None) == 2 and got == [7, 8, 9]
    assert hub.dispatch(timeout=0.05) == 0          # the pending wake was consumed: no event

"""Local TCP ports and polling waits: the one definition the launcher, the benchmarks and the
tests share.

Why here: a router's port is chosen at run time (never a fixed port: two runs, or two test
workers, on one machine) and every start-up waits for something to come up by polling with a
deadline, never by a fixed sleep.  ``tests/support.py`` re-exports these (its ``wait_until``
raises an AssertionError naming what it waited for).
"""

from __future__ import annotations

import socket
import time
from collections.abc import Callable

HOST = "127.0.0.1"


def free_port() -> int:
    """A TCP port on 127.0.0.1 that was free a moment ago (bind to port 0, read it, release)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind((HOST, 0))
        return int(sock.getsockname()[1])


def port_open(port: int, timeout_s: float = 0.2) -> bool:
    """Something listens on 127.0.0.1:``port``."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.settimeout(timeout_s)
        return sock.connect_ex((HOST, port)) == 0


def poll(predicate: Callable[[], bool], timeout_s: float, interval_s: float = 0.02,
         give_up: Callable[[], bool] = lambda: False) -> bool:
    """Call ``predicate`` every ``interval_s`` until it is true (True), ``timeout_s`` passes or
    ``give_up()`` is true (False); it is asked once more at the deadline."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if give_up():
            return False
        if predicate():
            return True
        time.sleep(interval_s)
    return bool(predicate())


def wait_for_port(port: int, timeout_s: float, give_up: Callable[[], bool] = lambda: False) -> bool:
    """Something listens on ``port`` within ``timeout_s`` (False on timeout or ``give_up``)."""
    return poll(lambda: port_open(port), timeout_s, interval_s=0.05, give_up=give_up)

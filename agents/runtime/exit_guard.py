"""A `chronav` process (a command or an agent) ends only once its own threads have: no daemon
thread may be inside a native call (Zenoh, Rerun) while the interpreter finalises.

Why: at finalisation CPython ends every daemon thread that tries to take the GIL back with
``pthread_exit``, a forced unwind.  A thread returning from a PyO3 call (a Zenoh ``get`` or a
channel's ``recv``, which release the GIL while they wait) unwinds through PyO3's
``catch_unwind``, which catches and drops the unwind, and glibc aborts the process:
``FATAL: exception not rethrown``, exit code 134, the result lost (seen once at the end of a
``chronav chaos`` run on a loaded machine; reproduced with a daemon thread looping on
``session.get`` when the process ends).  Closing the Zenoh sessions makes every such call
return, so the commands close what they opened (``dsr.join``'s ``with``, the chaos replica,
the recorder) and this guard, last thing in ``tools.cli.main`` and in an agent's
``agents.runtime.base.run_agent``, then waits for the daemon threads still running: a thread that returned from its native call finishes in Python, where
finalisation could not have aborted anything, but waiting costs nothing and leaves no doubt.

A thread that still runs after the grace period is named on stderr and the process ends with
``os._exit`` and the command's own exit code: skipping finalisation (and whatever exit handlers
had not run) is better than an abort that turns a finished run into a crash.

It lives in the agents' runtime so that both the agents and the commands (the layer above) can
reach it, in a package whose ``__init__`` imports nothing.  Imports only the standard library:
``chronav --help`` runs it too (tests/unit/test_cli_imports.py).
"""

from __future__ import annotations

import os
import sys
import threading
import time
import traceback
from typing import TextIO

#: how long the last moments of a process wait for its daemon threads (wall s): a thread blocked
#: in a native call of a closed session returns at once; a loaded machine may take a while to run it
GRACE_S = 10.0


def running_daemon_threads() -> list[threading.Thread]:
    """The daemon threads still alive, the calling thread excepted."""
    current = threading.current_thread()
    return [t for t in threading.enumerate() if t.daemon and t.is_alive() and t is not current]


def settle(grace_s: float | None = None) -> list[threading.Thread]:
    """Wait (at most `grace_s`, default GRACE_S, in all) for the daemon threads to end; those
    still running."""
    deadline = time.monotonic() + (GRACE_S if grace_s is None else grace_s)
    for thread in running_daemon_threads():
        thread.join(max(0.0, deadline - time.monotonic()))
    return running_daemon_threads()


def exit_code_of(code: object) -> int:
    """The process exit code `sys.exit(code)` gives (None: 0; a message: 1)."""
    if code is None:
        return 0
    return code if isinstance(code, int) else 1


def leave(code: object, grace_s: float | None = None, stderr: TextIO | None = None,
          what: str = "the command") -> None:
    """Return once no daemon thread runs, so that the interpreter may finalise; else name the
    threads still running and end the process at once with `code` (module docstring)."""
    grace_s = GRACE_S if grace_s is None else grace_s
    stragglers = settle(grace_s)
    if not stragglers:
        return
    out = stderr or sys.stderr
    frames = sys._current_frames()
    for thread in stragglers:
        frame = frames.get(thread.ident or -1)
        where = "" if frame is None else " at " + traceback.format_stack(frame, limit=1)[0].strip().splitlines()[0]
        out.write(f"chronav: thread {thread.name!r} still running {grace_s:g} s after {what} ended{where}; "
                  "exiting without interpreter shutdown\n")
    out.flush()
    sys.stdout.flush()
    os._exit(exit_code_of(code))

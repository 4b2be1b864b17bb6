"""Process lifecycle helpers for DSR processes (router, workers, tools).

Why: a Zenoh session with callback subscribers keeps non-daemon threads alive, so a process
that exits without closing it hangs forever.  Turning SIGTERM into SystemExit lets every
`finally:`/`with` block run and close its session, exactly like Ctrl-C does.
"""

from __future__ import annotations

import signal
import threading
from types import FrameType


def exit_on_sigterm() -> None:
    """Raise SystemExit(143) in the main thread on SIGTERM (SIGINT already raises
    KeyboardInterrupt).  No-op outside the main thread."""
    if threading.current_thread() is not threading.main_thread():
        return

    def _handler(signum: int, _frame: FrameType | None) -> None:
        raise SystemExit(128 + signum)

    signal.signal(signal.SIGTERM, _handler)

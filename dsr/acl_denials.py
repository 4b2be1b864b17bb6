"""The router's access-control refusals, counted and visible (`chronav dsr stats`, the log).

Why: Zenoh's ACL drops a denied message silently (the publisher sees no error) and says so only
in its own trace log, on stdout.  A tool publishing under another agent's name, or a host with
the wrong user, would go unnoticed.  The router process (dsr/router.py) therefore turns on
exactly that trace target (`zenoh::net::routing::interceptor::access_control=trace`: one line
per denied message, nothing per allowed one), reads Zenoh's log from a pipe in place of its
stdout, counts each denial by (user, message, key), logs the first 20 and then one summary line
every 10 s, and answers `chronav/<graph>/router?stats` with the counts.

The line parsed (eclipse-zenoh 1.10.2, verified on this machine):
`<zid> on Interface(lo)+Username(guest)+Transport(Tcp)+<zid> is unauthorized to Put (ingress)
on chronav/x/delta/sim_robot`.  Other Zenoh log lines of level WARN and ERROR are passed on to
the router's log; the rest is dropped (as before: the router printed no Zenoh log at all).
"""

from __future__ import annotations

import os
import re
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

import orjson

FORMAT = "chronav-router-stats/1"
ENCODING = "application/json;chronav-router-stats/1"
_TARGET = "zenoh::net::routing::interceptor::access_control"
_ANSI = re.compile(r"\x1b\[[0-9;]*m")
_DECISION = re.compile(r"(?P<thread>ThreadId\(\d+\)).*?access_control: (?P<cached>Using cached "
                       r"result: )?(?P<zid>[0-9a-f]+)(?: on \S*?Username\((?P<user>[^)]*)\)\S*)? "
                       r"is (?P<verdict>un)?authorized to (?P<message>.+?) \((?P<flow>\w+)\) on "
                       r"(?P<key>\S+)")
_CACHING = re.compile(r"(?P<thread>ThreadId\(\d+\)).*?caching permissions for `(?P<key>[^`]*)`")
_LOG_FIRST = 20
_SUMMARY_EVERY_S = 10.0
_MAX_KINDS = 1000


def stats_key(graph: str) -> str:
    """Where the router answers with its counts (under the graph's key space, so the run's ACL
    lets every run user ask)."""
    return f"chronav/{graph}/router"


class AclDenials:
    """Counts of denied messages by (user, message kind, flow, key); thread-safe."""

    def __init__(self, out: Callable[[str], None] | None = None, *, counting: bool = True) -> None:
        #: False: the router runs without an ACL (nothing is denied, nothing is counted)
        self.counting = counting
        self.total = 0
        self.by_kind: dict[tuple[str, str, str, str], int] = {}
        self._lock = threading.Lock()
        self._out = out or (lambda line: print(line, flush=True))
        self._last_summary = 0.0
        self._unlogged = 0
        #: thread -> key whose permissions Zenoh is precomputing (see on_log_line)
        self._caching: dict[str, str] = {}
        #: session id -> user name, from Zenoh's lines that name both
        self._users: dict[str, str] = {}

    def on_log_line(self, line: str) -> None:
        """One line of Zenoh's log.  A key expression declared by a client (a publisher, a
        queryable, a token) makes the ACL precompute every kind of message on it ("caching
        permissions for `key`", then one line per kind): those lines decide nothing and are
        skipped; the decisions themselves follow ("Using cached result: ...", or a line of
        its own for a key that was not declared)."""
        text = _ANSI.sub("", line).rstrip()
        if _TARGET not in text:
            if " WARN " in text or " ERROR " in text:
                self._out(text)
            return
        caching = _CACHING.search(text)
        if caching is not None:
            self._caching[caching["thread"]] = caching["key"]
            return
        match = _DECISION.search(text)
        if match is None:
            return
        if match["user"]:
            self._users[match["zid"]] = match["user"]
        if not match["cached"] and self._caching.get(match["thread"]) == match["key"]:
            return                         # part of the precomputation: not a message
        self._caching.pop(match["thread"], None)
        if not match["verdict"]:
            return
        user = match["user"] or self._users.get(match["zid"], f"zid {match['zid']}")
        kind = (user, match["message"].lower().replace("declare/undeclare ", "declare "),
                match["flow"], match["key"])
        now = time.monotonic()
        with self._lock:
            self.total += 1
            if kind in self.by_kind or len(self.by_kind) < _MAX_KINDS:
                self.by_kind[kind] = self.by_kind.get(kind, 0) + 1
            if self.total <= _LOG_FIRST:
                line_out = (f"dsr.router: ACL denied {kind[1]} ({kind[2]}) on {kind[3]} by user "
                            f"{kind[0]!r} ({self.total} denied so far)")
            elif now - self._last_summary >= _SUMMARY_EVERY_S:
                line_out = (f"dsr.router: ACL denied {self._unlogged + 1} more messages "
                            f"({self.total} in all); latest: {kind[1]} on {kind[3]} by user "
                            f"{kind[0]!r}")
                self._unlogged = 0
            else:
                self._unlogged += 1
                return
            self._last_summary = now
        self._out(line_out)

    def report(self) -> dict[str, Any]:
        with self._lock:
            kinds = sorted(self.by_kind.items(), key=lambda item: -item[1])
            return {"format": FORMAT, "acl": self.counting, "acl_denied": self.total,
                    "denials": [{"user": u, "message": m, "flow": f, "key": k, "count": n}
                                for (u, m, f, k), n in kinds[:100]]}

    def on_query(self, query: Any) -> None:
        try:
            query.reply(str(query.key_expr), orjson.dumps(self.report()), encoding=ENCODING)
        except Exception:  # noqa: BLE001 - a stats query must never take the router down
            pass


def capture_zenoh_log(on_line: Callable[[str], None]) -> None:
    """Read Zenoh's log (it writes to fd 1) through a pipe, line by line, on a daemon thread;
    Python's own prints keep going to the real stdout.  Turns on the ACL trace target."""
    import zenoh

    real = os.dup(1)
    sys.stdout.flush()
    sys.stdout = os.fdopen(real, "w", buffering=1)
    read_end, write_end = os.pipe()
    os.dup2(write_end, 1)
    os.close(write_end)

    def pump() -> None:
        with os.fdopen(read_end, "r", errors="replace") as lines:
            for line in lines:
                on_line(line)

    threading.Thread(target=pump, name="router-log", daemon=True).start()
    spec = os.environ.get("RUST_LOG") or "warn"
    os.environ["RUST_LOG"] = f"{spec},{_TARGET}=trace"
    os.environ.setdefault("NO_COLOR", "1")
    zenoh.try_init_log_from_env()

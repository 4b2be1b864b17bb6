"""Anti-entropy of a replica: when to fetch another member's state, and the loop that does it.

Why its own module: Zenoh loses the puts made while a session is cut off, so a replica must
notice that it lags (a member's digest announces writes it lacks; a member (re)appears; its
own connection comes back) and fetch a state.  Deciding *when* (grace period for deltas in
flight, a per-member rate limit, one pending request per member) is policy with its own
state and tests (tests/unit/test_dsr_fetch_rate.py); `Replica` (dsr/transport.py) supplies the
I/O: fetching a state, publishing a digest.
"""

from __future__ import annotations

import logging
import queue
import random
import threading
import time
from collections.abc import Callable

from dsr import wire
from dsr.membership import Member, Membership

log = logging.getLogger(__name__)
ALL = "*"


class AntiEntropy:
    """Sync requests of one replica and the rules that raise them from digests."""

    def __init__(self, membership: Membership, owner_of: Callable[[int], str | None],
                 digest_interval: float = 0.5, max_fetch_backoff_s: float = 30.0) -> None:
        self.membership = membership
        self._owner_of = owner_of
        #: how often a digest is published, tombstones compacted and lags checked
        self.digest_interval = digest_interval
        #: how long a member must hold writes we lack before we fetch a state for them
        self.lag_grace_s = 4 * digest_interval
        #: longest pause between two digest-triggered state fetches of one member
        self.max_fetch_backoff_s = max_fetch_backoff_s
        #: monotonic clock of the timers (tests replace it)
        self.now: Callable[[], float] = time.monotonic
        #: member -> (no digest-triggered fetch before, pause after the next one, last fetch)
        self._backoff: dict[str, tuple[float, float, float]] = {}
        #: agents whose state is to be fetched ('*': every member; None: stop the loop)
        self.requests: queue.Queue[str | None] = queue.Queue()
        self._pending: set[str] = set()
        self._lock = threading.Lock()
        self.postponed = 0

    # ------------------------------------------------------------------ requests
    def request(self, agent: str) -> None:
        """Queue a state fetch, once: digests of several members may point at the same one."""
        with self._lock:
            if agent in self._pending:
                return
            self._pending.add(agent)
        self.requests.put(agent)

    def take(self, timeout: float | None = None) -> str | None:
        """The next requested fetch ('' if none came within `timeout`; None: stop); it may be
        requested again from now on."""
        try:
            agent = self.requests.get(timeout=timeout) if timeout is None or timeout > 0 \
                else self.requests.get_nowait()
        except queue.Empty:
            return ""
        if agent:
            with self._lock:
                self._pending.discard(agent)
        return agent

    def stop(self) -> None:
        self.requests.put(None)

    def join_round(self, members: list[str], sync: Callable[[str], int]) -> None:
        """A joiner's first round: one member's complete state is enough to start (merging
        every member's copy of a large graph would multiply the join time).  Members are tried
        in random order (spreading the load when many agents start together); a member whose
        state covers every running member (its `seen` has as many writers) is a complete
        copy; a tool that serves only its own writes is not: merge it and go on
        (docs/dsr_wire_format.md, "Writing as a foreign client").  `sync(agent)` fetches and
        merges a state, returning how many replies were merged."""
        members = list(members)
        random.shuffle(members)
        for member in members:
            self.membership.state_cover = 0
            if sync(member) and self.membership.state_cover >= len(members):
                return
        if not members:
            sync(ALL)

    # ------------------------------------------------------------------ digests
    def lagging(self, message: wire.Decoded) -> set[str]:
        """The members to fetch a state from after this digest (already rate-limited)."""
        membership = self.membership
        mine = membership.my_replica
        with membership.lock:
            member = membership.members.get(message.agent)
            if member is None or member.replica != message.replica:
                member = membership.members[message.agent] = Member(message.agent,
                                                                    message.replica)
            member.clock, member.seen, member.live = message.clock, message.seen, True
            seen = membership.seen
            # The member holds writes we lack.  Deltas in flight, or a backlog on a loaded
            # machine, look the same for a while: only a lag that lasts lag_grace_s (and at
            # most once per lag_grace_s per writer) fetches a state.
            now = self.now()
            since = member.behind
            for replica, hlc in message.seen.items():
                if replica != mine and hlc > seen.get(replica, 0) and replica not in since:
                    since[replica] = (hlc, now)
            targets: set[str] = set()
            if message.agent not in membership.vouched:
                # its own state (this incarnation) is not merged here yet: until it is, its
                # watermark and its replica ids are unknown here and claims about it are
                # deferred; fetch it now (also how a member answers a forged claim about it)
                targets.add(message.agent)
            for replica, (hlc, at) in list(since.items()):
                if seen.get(replica, 0) >= hlc:
                    del since[replica]
                elif now - at >= self.lag_grace_s:
                    # fetch from the writer itself if it runs (only its own state is
                    # trusted for its writes), else from the member that holds them
                    owner = self._owner_of(replica)
                    known = membership.members.get(owner) if owner is not None else None
                    targets.add(owner if owner is not None and known is not None and known.live
                                else message.agent)
                    since[replica] = (message.seen.get(replica, hlc), now)
            return {t for t in targets if self._fetch_allowed(t, now)}

    def _fetch_allowed(self, target: str, now: float) -> bool:
        """Rate limit of the state fetches digests ask for, per member: the first at once,
        the next ones after a pause that doubles (lag_grace_s, 2x, 4x ... up to
        max_fetch_backoff_s) as long as digests keep asking (a member whose state is
        refused, or that keeps announcing writes its state does not carry; or this replica
        is so loaded that it lags behind its own queue of deltas: fetching a state then
        makes it slower still).  The pause starts again from lag_grace_s only after a quiet
        period of twice the longest pause.  So a member costs one fetch per change it makes
        (a lost delta), and at most one per max_fetch_backoff_s when something keeps them
        coming.  Caller holds the membership lock."""
        base, longest = self.lag_grace_s, self.max_fetch_backoff_s
        not_before, pause, last = self._backoff.get(target, (0.0, base, -2 * longest))
        if now < not_before:
            self.postponed += 1
            return False
        if now - last >= 2 * longest:
            pause = base
        self._backoff[target] = (now + pause, min(2 * pause, longest), now)
        return True

    # ------------------------------------------------------------------ the loop
    def run(self, closed: threading.Event, *, name: str, connected: Callable[[], bool],
            sync: Callable[[str], object], maintain: Callable[[], None],
            on_error: Callable[[], None], was_connected: bool,
            watch_interval: float = 0.5) -> None:
        """The sync worker: fetch requested states; every digest_interval, if connected, one
        round of upkeep (`maintain`: digest out, tombstones compacted).  When the connection
        comes back, every watermark is void and every member's state is fetched."""
        next_digest = time.monotonic()
        while not closed.is_set():
            timeout = max(0.0, min(watch_interval, next_digest - time.monotonic()))
            agent = self.take(timeout)
            if agent is None or closed.is_set():
                return
            try:
                now_connected = connected()
                if now_connected and not was_connected:
                    log.info("DSR %s: connection back, resynchronising", name)
                    self.membership.lost_everything()
                    agent = ALL
                was_connected = now_connected
                if agent:
                    sync(agent)
                if time.monotonic() >= next_digest:
                    next_digest = time.monotonic() + self.digest_interval
                    if now_connected:
                        maintain()
            except Exception:  # session closed under us, or a bad reply
                if closed.is_set():
                    return
                on_error()
                log.exception("DSR %s: anti-entropy round failed", name)

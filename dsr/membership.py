"""Membership of a replica: who else writes the graph, and how far this replica has caught up.

Why its own module: `Replica` (dsr/transport.py) binds a graph to Zenoh; what it knows of the
other members (from their liveliness tokens and digests) and the watermarks of what it holds
of each writer are state of their own, read by the admission of states (dsr/state_trust.py
screening), by anti-entropy (dsr/anti_entropy.py: who lags) and by tombstone compaction
(`acked`).  One lock guards all of it; nothing here does I/O.

Watermarks: seen[z] = this replica holds every write replica z stamped up to seen[z].  A
running writer's entry is set only by its own state (`note_state`) and then moved on by its
own deltas and digests (`advance`); without an entry its relayed writes wait for it
(deferred, dsr/state_trust.py).
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from dsr import wire

if TYPE_CHECKING:
    from dsr.bindings import WriterBindings


@dataclass
class Member:
    """What this replica knows of another writable member, from its digests."""

    agent: str
    replica: int = 0
    clock: int = 0
    seen: dict[int, int] = field(default_factory=dict)
    live: bool = True
    gone_at: float = 0.0
    #: writer replica -> (stamp this member holds and we lacked, since when)
    behind: dict[int, tuple[int, float]] = field(default_factory=dict)


class Membership:
    """The member table and the watermarks of one replica (thread-safe: one lock)."""

    def __init__(self, me: str, bindings: WriterBindings, my_replica: int,
                 retention_s: float = 60.0) -> None:
        self.me = me
        self.my_replica = my_replica
        #: a member that left still counts for tombstone compaction this long (a partitioned
        #: member must not come back with elements everybody else forgot)
        self.retention_s = retention_s
        #: the graph's writer bindings: whose watermarks to forget, who owns a replica id
        self._bindings = bindings
        self.lock = threading.Lock()
        self.members: dict[str, Member] = {}
        self.seen: dict[int, int] = {}
        #: agents whose own state (this incarnation) has been merged: their replica ids known
        self.vouched: set[str] = set()
        #: writers the `seen` of the last state merged covers (completeness of a join's copy)
        self.state_cover = 0

    # ------------------------------------------------------------------ members
    def add(self, agent: str) -> Member:
        """A member known to be running (its token is up), unless already known."""
        with self.lock:
            return self.members.setdefault(agent, Member(agent))

    def presence(self, agent: str, live: bool) -> None:
        """A member's token appeared or vanished.  Either way its stream may have a gap (a
        broken session loses puts): until its own state is merged again, its watermarks and
        replica ids are not trusted."""
        with self.lock:
            member = self.members.get(agent)
            if member is None:
                member = self.members[agent] = Member(agent)
            member.live = live
            member.gone_at = 0.0 if live else time.monotonic()
            self._gap(agent)
            self.vouched.discard(agent)

    def live_agents(self) -> set[str]:
        with self.lock:
            return {m.agent for m in self.members.values() if m.live}

    def summary(self) -> dict[str, dict[str, object]]:
        """agent -> {replica, live} (what `chronav dsr stats` shows)."""
        with self.lock:
            return {m.agent: {"replica": m.replica, "live": m.live}
                    for m in self.members.values()}

    def acked(self, replica: int, hlc: int) -> bool:
        """Every member (running, or gone less than retention_s ago) has told us, in its
        digest, that it holds every write of `replica` up to `hlc`."""
        now = time.monotonic()
        with self.lock:
            for member in self.members.values():
                if not member.live and now - member.gone_at > self.retention_s:
                    continue
                if member.seen.get(replica, 0) < hlc:
                    return False
        return True

    # ------------------------------------------------------------------ watermarks
    def watermarks(self) -> dict[int, int]:
        with self.lock:
            return dict(self.seen)

    def trust_snapshot(self) -> tuple[dict[int, int], set[str]]:
        """(watermarks, vouched agents), copied: what screening a state needs."""
        with self.lock:
            return dict(self.seen), set(self.vouched)

    def advance(self, replica: int, hlc: int) -> None:
        """A writer's own messages arrive in order: we now hold all it stamped up to hlc, if
        we held all it stamped before the first of them that reached us.  Only its own state
        proves that (it sets the entry, `note_state`): a subscription takes effect at the
        router a moment after it is declared, a broken session loses the puts made meanwhile,
        and in both cases the deltas that do arrive come in order after a hole.  So without an
        entry, nothing is advanced."""
        with self.lock:
            current = self.seen.get(replica)
            if current is not None and hlc > current:
                self.seen[replica] = hlc

    def lost_everything(self) -> None:
        """The connection came back: deltas were lost meanwhile, every watermark is void."""
        with self.lock:
            self._gap(None)

    def _gap(self, agent: str | None) -> None:
        """Deltas of `agent` (None: of everybody) may have been lost: forget its watermarks
        until its own state has been merged again.  Caller holds the lock."""
        for replica, owner in list(self._bindings.bound.items()):
            if replica != self.my_replica and (agent is None or owner == agent):
                self.seen.pop(replica, None)

    def note_state(self, message: wire.Decoded) -> None:
        """After merging a state: we now hold what its sender held of its own writes, and of
        the writes of agents that are not running.  A running writer's watermark comes only
        from its own state, even in the first state of a join: its relayed stamps may have
        been screened out, and deltas it published while our subscription was taking effect
        may be missing here though the relay holds them (`advance`)."""
        sender = message.agent
        live = self.live_agents()
        with self.lock:
            if message.clock:                   # the last part of the state: all merged
                self.vouched.add(sender)
                self.state_cover = len(message.seen)
            for replica, hlc in message.seen.items():
                owner = self._bindings.bound_agent(replica) or message.writers.get(str(replica))
                own = replica == message.replica or owner == sender
                if not own and owner in live:
                    continue    # a running writer: only its own state sets its watermark
                if hlc >= self.seen.get(replica, 0):   # (one that is not running sends
                    self.seen[replica] = hlc          # nothing more: a relay's is true)

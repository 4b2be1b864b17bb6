"""Which agent each replica id writes for, as far as one replica knows.

Why its own class: every stamp in the graph names a replica id, and write policies, state
screening (dsr/state_trust.py) and state replies need the agent behind it.  Two tables with
different trust: `bound` holds bindings known first-hand (a message on that agent's own key,
that agent's own state, or the state this replica joined with) and is what this replica serves
in its state replies; `attributed` adds bindings only relayed by another member's state about
an agent that is not running: used to attribute that replica's writes to the write policy,
never served (a relay proves nothing).
"""

from __future__ import annotations

import threading
from collections.abc import Mapping


class WriterBindings:
    """replica id -> agent, first-hand (`bound`) and attributed (`attributed` ⊇ `bound`)."""

    def __init__(self, replica: int, agent: str, lock: threading.RLock) -> None:
        self._lock = lock                  # the graph's lock: bindings change with merges
        self.bound: dict[int, str] = {replica: agent}
        self.attributed: dict[int, str] = {replica: agent}

    def bound_agent(self, replica: int) -> str | None:
        """The agent of a replica id known first-hand (dsr/state_trust.py)."""
        return self.bound.get(replica)

    def writer_agent(self, replica: int) -> str | None:
        """The agent a replica id writes for, first-hand or relayed."""
        return self.attributed.get(replica)

    def note(self, replica: int, agent: str) -> None:
        """Record a first-hand binding (it replaces a relayed one: what the agent's own key
        says beats what a relay said).  The first binding of a replica id stays."""
        if self.bound.get(replica) != agent:
            with self._lock:
                if replica not in self.bound:
                    self.bound[replica] = agent
                    self.attributed[replica] = agent

    def note_relayed(self, replica: int, agent: str) -> None:
        """Record a binding only relayed by another member's state (an agent that is not
        running): attribution only."""
        if replica not in self.attributed:
            with self._lock:
                self.attributed.setdefault(replica, agent)

    def vouch(self, writers: Mapping[str, str], sender: int | None, agent: str) -> None:
        """Whoever hands a message to DSRGraph.apply_message vouches for its `writers` (the
        transport judges a state's table itself and passes none: admission.note_state_writers) and,
        for a delta, for its sender (`sender`, None for a state).  Caller holds the lock."""
        bound, attributed = self.bound, self.attributed
        for key, name in writers.items():
            replica = int(key)
            if replica not in bound:
                bound[replica] = attributed[replica] = name
        if sender is not None and sender not in bound:
            bound[sender] = attributed[sender] = agent

    def served(self) -> dict[int, str]:
        """The `writers` table of this replica's state replies: only bindings it can prove."""
        with self._lock:
            return dict(self.bound)

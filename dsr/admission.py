"""Admission checks: what a received delta, digest or state must satisfy before it touches
the graph (docs/dsr_wire_format.md, "Validation").

Why its own module: these rules are pure functions of the message and of what the local graph
knows (writer bindings, clock, the states it holds), with many cases each tested on its own;
`Replica.admit_delta` / `admit_state` (dsr/transport.py) run them in order, then the write
policy (dsr/policy.py), then merge.  Each returns None or (reason, text): the reason is one of
REASONS (counted and logged per reason by the replica), the text says what was wrong.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from dsr import wire
from dsr.limits import node_problem

if TYPE_CHECKING:
    from dsr.bindings import WriterBindings
    from dsr.graph import DSRGraph

Problem = tuple[str, str]
_LOG_FIRST_REJECTS = 20

#: reasons a received message (or part of a state) is refused; counted one by one
REASONS = ("invalid", "too_large", "wrong_graph", "wrong_kind", "forged_writer", "forged_stamp",
           "clock_ahead", "removal_receipt", "policy", "too_many_attrs", "node_too_large")


class LogBudget:
    """Per-reason log rate limit: the first `burst` refusals of a reason are logged, then at
    most one line per `period_s` saying how many were not logged in between."""

    def __init__(self, burst: int = _LOG_FIRST_REJECTS, period_s: float = 10.0) -> None:
        self.burst, self.period_s = burst, period_s
        self._count: dict[str, int] = {}
        self._last: dict[str, float] = {}
        self._quiet: dict[str, int] = {}

    def allow(self, reason: str) -> tuple[bool, int]:
        """(log this one?, how many of this reason went unlogged since the last line)"""
        count = self._count.get(reason, 0) + 1
        self._count[reason] = count
        now = time.monotonic()
        if count <= self.burst or now - self._last.get(reason, 0.0) >= self.period_s:
            self._last[reason] = now
            return True, self._quiet.pop(reason, 0)
        self._quiet[reason] = self._quiet.get(reason, 0) + 1
        return False, 0


def message_problem(graph: DSRGraph, message: wire.Decoded, claimed: str,
                    kind: str) -> Problem | None:
    """What is wrong with a decoded message received on the key of agent `claimed` for a
    `kind` ("delta": deltas and digests, or "state") message, before any policy: kind, graph,
    writer identity, stamps of other writers, removal receipts, clock."""
    if message.kind != kind and not (kind == "delta" and message.kind == "digest"):
        return "wrong_kind", f"a {message.kind!r} message on a {kind} key"
    problem = _identity_problem(graph, message, claimed)
    if problem is None:
        problem = _state_problem(graph, message) if kind == "state" \
            else _delta_problem(message)
    if problem is not None:
        return problem
    top = message.top_hlc
    if top and graph.clock.too_far_ahead(top):
        return "clock_ahead", (f"clock {top} is more than {graph.clock.max_offset_ms} ms "
                               "ahead of this replica's wall clock")
    return None


def _identity_problem(graph: DSRGraph, message: wire.Decoded, claimed: str) -> Problem | None:
    if message.graph != graph.graph_name:
        return "wrong_graph", (f"message for graph {message.graph!r}, this is "
                               f"{graph.graph_name!r}")
    if message.agent != claimed:
        return "forged_writer", (f"forged writer: claims agent {message.agent!r} on the "
                                 f"key of {claimed!r}")
    if message.replica == graph.replica_id:
        return "forged_writer", f"forged writer: uses this replica's id {message.replica}"
    owner = graph.writers.bound_agent(message.replica)
    if owner is not None and owner != message.agent:
        return "forged_writer", (f"forged writer: replica id {message.replica} belongs to "
                                 f"agent {owner!r}")
    return None


def _state_problem(graph: DSRGraph, message: wire.Decoded) -> Problem | None:
    bound_agent = graph.writers.bound_agent
    for replica, agent in message.writers.items():
        known = bound_agent(int(replica))
        if known is not None and known != agent:
            return "forged_writer", (f"forged writer: state says replica {replica} is "
                                     f"{agent!r}, it is {known!r}")
    removal = wire.removal_problem(message)
    if removal is not None:
        return "removal_receipt", removal
    return None


def _delta_problem(message: wire.Decoded) -> Problem | None:
    if message.writers:
        return "invalid", "a delta must not carry 'writers'"
    if message.kind == "digest" and (message.nodes or message.edges):
        return "invalid", "a digest must not carry nodes or edges"
    if message.edges or any(state.add or state.meta is not None or state.rem
                            or state.cleared for _, state in message.nodes):
        foreign = wire.foreign_writer(message)
        if foreign is not None:
            return "forged_writer", (f"forged writer: delta of replica "
                                     f"{message.replica} carries {foreign}")
        removal = wire.removal_problem(message)
        if removal is not None:
            return "removal_receipt", removal
        return None
    own = message.replica                   # attribute updates only (the hot path)
    for _, state in message.nodes:
        for attr, reg in state.attrs.items():
            if reg[1] != own:
                return "forged_writer", (
                    f"forged writer: delta of replica {own} carries attribute "
                    f"{attr!r} written by replica {reg[1]}")
    return None


def delta_node_problem(graph: DSRGraph, message: wire.Decoded) -> Problem | None:
    """A delta that would take a node over the node limits (dsr/limits.py) is refused whole.
    Scalars written over keys the node already has cannot grow it: skipped without counting
    (the common update, on the hot path)."""
    held = graph.node_states.get
    for node_id, state in message.nodes:
        attrs = state.attrs
        if not attrs:
            continue
        current = held(node_id)
        if current is not None:
            if len(attrs) == 1:             # (the common update: one key)
                ((name, reg),) = attrs.items()
                kind = type(reg[2])
                if name in current.attrs and kind is not str and kind is not list:
                    continue
            elif attrs.keys() <= current.attrs.keys():
                for reg in attrs.values():
                    kind = type(reg[2])
                    if kind is str or kind is list:
                        break
                else:
                    continue
        problem = node_problem(node_id, current.attrs if current is not None else None,
                               attrs, registers=True)
        if problem is not None:
            return problem
    return None


def within_node_limits(graph: DSRGraph, nodes: list[tuple[int, Any]]
                       ) -> tuple[list[tuple[int, Any]], dict[str, tuple[str, int]]]:
    """A state's node entries minus those that would take a node over the node limits, and
    the problems: reason -> (text of the first, how many nodes)."""
    held = graph.node_states.get
    kept = []
    problems: dict[str, tuple[str, int]] = {}
    for node_id, state in nodes:
        if state.attrs:
            current = held(node_id)
            problem = node_problem(node_id, current.attrs if current is not None else None,
                                   state.attrs, registers=True)
            if problem is not None:
                first, count = problems.get(problem[0], (problem[1], 0))
                problems[problem[0]] = (first, count + 1)
                continue
        kept.append((node_id, state))
    return kept, problems


def note_state_writers(bindings: WriterBindings, me: str, sender: str,
                       writers: Mapping[str, str], live: set[str], *, joined: bool) -> None:
    """Which `writers` entries of a merged state this replica takes as its own knowledge
    (and will serve in its state replies: DSRGraph.served_writers), and which only to
    attribute relayed writes (dsr/state_trust.py):
    - the sender's own replica ids (an agent vouches for its incarnations): proven (after
      the join, the screening has removed every entry naming this replica's own agent
      that it does not know: state_trust.screen_state);
    - every entry of the first state of a join (`joined` False): nothing to check it against,
      trusted (documented limit; its sender served only what it could prove).  Entries about
      running agents included: a joiner that left them out would relay their writes
      without attribution to the next joiner, whose policy would refuse them;
    - after the join, an entry about an agent that is not running: attribution only, never
      served (a relay proves nothing); about a running agent: nothing (deferred until that
      agent's own messages or state say it)."""
    for key, agent in writers.items():
        replica = int(key)
        if bindings.bound_agent(replica) is not None:
            continue
        if agent == sender or agent == me or not joined:
            bindings.note(replica, agent)
        elif agent not in live:
            bindings.note_relayed(replica, agent)

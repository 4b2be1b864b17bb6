"""Replication of a DSRGraph over Zenoh (key space and format: docs/dsr_wire_format.md).

- Local deltas are published on ``chronav/<graph>/delta/<agent>`` (reliable, BLOCK congestion
  control: a CRDT delta must never be silently dropped by a full queue).
- Remote deltas arrive on ``chronav/<graph>/delta/*``; each is validated (schema, claimed agent
  == key, writer ids, clock drift) and checked against the write policy (dsr/policy.py) before
  it touches the graph; state replies too.  Rejected ones are
  logged and counted in `ReplicaStats`, and the graph is untouched.  Deltas wait in a Zenoh
  channel and are handled one at a time in arrival order, by the replica's receiver thread or,
  while the agent's thread polls in dispatch(), by that thread (dsr/receiver.py).
- State transfer: each writable replica answers ``chronav/<graph>/state/<agent>`` with its full
  CRDT state.  A replica queries ``state/*`` when it starts, and again whenever its connection
  comes back (puts made while disconnected are lost by Zenoh, so this anti-entropy is needed).
- Presence: a liveliness token ``chronav/<graph>/members/<agent>``; when a member (re)appears,
  the others query its state, which carries what it wrote while it was cut off.

This module is the lifecycle and the Zenoh I/O; beside it: dsr/admission.py (the checks a
received message must pass), dsr/membership.py (members and watermarks), dsr/anti_entropy.py
(when to fetch a state, and the sync loop).  `Replica.admit_delta` / `admit_state` are the one
door a received message goes through, with or without Zenoh (tests use them directly).
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from typing import Any

import orjson

from dsr import wire
from dsr.admission import (REASONS, LogBudget, delta_node_problem, message_problem,
                           note_state_writers, within_node_limits)
from dsr.anti_entropy import ALL, AntiEntropy
from dsr.collector import FREEZE_AFTER_JOIN_NODES, gc_paused, tune_collector
from dsr.config import ZenohSettings, clean_zenoh_error, graph_name_from_env
from dsr.errors import DSRError, WireError
from dsr.graph import DSRGraph
from dsr.limits import LIMITS
from dsr.membership import Member, Membership
from dsr.policy import AllowAll, WritePolicy
from dsr.receiver import DeltaReceiver, receiver_of
from dsr.signals import SpinPolicy

log = logging.getLogger(__name__)
__all__ = ["REASONS", "Member", "Replica", "ReplicaStats", "TransportError", "join",
           "delta_publisher_options"]
#: members whose delta key a session declares (Replica._declare_writer_key); past this many the
#: wildcard subscription still delivers every delta, only without the shortcut
MAX_DECLARED_WRITER_KEYS = 256
STATS_FORMAT = "chronav-dsr-stats/1"
STATS_ENCODING = "application/json;chronav-dsr-stats/1"


class TransportError(DSRError, ConnectionError):
    """The Zenoh session could not be opened (router not reachable, bad endpoint...)."""


@dataclass
class ReplicaStats:
    """Counters of one replica; written by Zenoh callback threads, read by anyone."""

    received: int = 0           # remote delta (and digest) samples received
    applied: int = 0            # remote deltas merged
    rejected: int = 0           # invalid messages dropped (schema, forged writer, clock...)
    rejected_policy: int = 0    # valid deltas/states refused (in part) by the write policy
    published: int = 0          # local deltas published
    state_served: int = 0       # state queries answered
    state_merged: int = 0       # state replies merged
    syncs: int = 0              # anti-entropy rounds (initial join included)
    errors: int = 0             # unexpected exceptions inside callbacks
    received_by_agent: int = 0  # remote deltas handled by an agent thread polling in dispatch()
    last_reject: str = ""
    #: refusals per reason (see REASONS); each reason has its own log budget
    rejects: dict[str, int] = field(default_factory=dict)
    deferred: int = 0           # relayed stamps of running writers left for the writer itself
    digests_sent: int = 0
    digests_received: int = 0
    anti_entropy: int = 0       # syncs started because a member's digest showed we lag
    fetches_postponed: int = 0  # digest-triggered state fetches held back by the rate limit
    forgeries_about_me: int = 0  # states forging a claim about this agent (answered at once)
    compacted: int = 0          # tombstones forgotten once every member had seen the removal
    tombstones: int = 0         # tombstones held (at the last digest)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def delta_publisher_options(zenoh: Any) -> dict[str, Any]:
    """The options of a replica's delta publisher (docs/dsr_wire_format.md, "Key space")."""
    return {"encoding": wire.ENCODING, "congestion_control": zenoh.CongestionControl.BLOCK,
            "reliability": zenoh.Reliability.RELIABLE}



class Replica:
    """Binds a DSRGraph to a Zenoh session.  Use `join()` or `with Replica(...) as replica:`.

    Received messages go through the public admission API, `admit_delta` and `admit_state`
    (what the Zenoh callbacks call, and what tests call without a network); who the other
    members are and how far this replica has caught up is `members` (dsr/membership.py);
    when to fetch a state is `anti_entropy` (dsr/anti_entropy.py)."""

    def __init__(self, graph: DSRGraph, settings: ZenohSettings | None = None, *,
                 policy: WritePolicy | None = None, sync_timeout: float = 10.0,
                 watch_interval: float = 0.5, linger_s: float = 0.0003,
                 digest_interval: float = 0.5, member_retention_s: float = 60.0) -> None:
        self.graph = graph
        self.settings = settings or ZenohSettings.from_env()
        self.policy: WritePolicy = policy or AllowAll()
        self.sync_timeout = sync_timeout
        self.watch_interval = watch_interval
        self.linger_s = linger_s
        self.members = Membership(graph.agent, graph.writers, graph.replica_id,
                                  retention_s=member_retention_s)
        self.anti_entropy = AntiEntropy(self.members, graph.writers.bound_agent,
                                        digest_interval=digest_interval)
        self.stats = ReplicaStats()
        self._log_budget = LogBudget()
        self.session: Any = None
        self._publisher: Any = None
        self._token: Any = None
        self._entities: list[Any] = []
        self._worker: threading.Thread | None = None
        self._closed = threading.Event()
        #: True once the first state has been merged (open(); a test acting as a running
        #: replica sets it): states merged later are screened (dsr/state_trust.py)
        self.joined = False
        #: takes received deltas off the Zenoh channel (dsr/receiver.py; None until opened)
        self._receiver: DeltaReceiver | None = None
        #: agent -> the Zenoh KeyExpr of its delta key, declared in this session
        self._writer_keys: dict[str, Any] = {}
        self._writer_keys_lock = threading.Lock()
        name = graph.graph_name
        self._delta_key = wire.delta_key(name, graph.agent)
        self._state_key = wire.state_key(name, graph.agent)
        self._member_key = wire.member_key(name, graph.agent)
        if not isinstance(self.policy, AllowAll) and hasattr(self.policy, "refusal"):
            graph.local_policy = self.policy
        self._checks_deltas = not isinstance(self.policy, AllowAll)

    # ------------------------------------------------------------------ lifecycle
    def __enter__(self) -> Replica:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def open(self) -> None:
        """Open the session, declare entities, fetch the current state (blocking)."""
        import zenoh

        tune_collector()     # a replica's heap is long-lived and acyclic: dsr/collector.py
        conf = self.settings.to_zenoh_config()
        self._tune(conf)
        try:
            self.session = zenoh.open(conf)
        except zenoh.ZError as exc:
            raise TransportError(f"cannot open Zenoh session ({self.settings.describe()}): "
                                 f"{clean_zenoh_error(exc)}; "
                                 "is a router running (python -m dsr.router --listen ...)?"
                                 ) from None
        register_atexit = getattr(threading, "_register_atexit", None)
        if register_atexit is not None:  # close before the interpreter joins Zenoh's threads
            register_atexit(self.close)
        try:
            self._declare(zenoh)
            connected = self._is_connected()
            # Join: one member's complete state is enough to start (merging every member's
            # copy of a large graph would multiply the join time); then a background round
            # merges every other replica's state, which covers deltas that were in flight
            # while the answer was built and anything the first member lacked.
            with gc_paused(freeze_if=lambda: len(self.graph) >= FREEZE_AFTER_JOIN_NODES):
                self._initial_sync()
            self.joined = True
            self.anti_entropy.request(ALL)
            if not self.graph.read_only:
                self.graph.attach(self._publish, linger_s=self.linger_s)
            self.graph.receive_while_polling(self._receiver)
            self._worker = threading.Thread(target=self._work, args=(connected,),
                                            name=f"dsr-sync-{self.graph.agent}", daemon=True)
            self._worker.start()
        except BaseException:
            self.close()
            raise
        self.graph.replica = self

    def _tune(self, conf: Any) -> None:
        """Reconnect fast after a partition heals (Zenoh's client backoff grows to 4 s)."""
        import json
        if self.settings.config_file is not None:
            return                      # an operator's config file decides
        try:
            conf.insert_json5("connect/retry", json.dumps(
                {"period_init_ms": 200, "period_max_ms": 500, "period_increase_factor": 1.5}))
        except Exception:  # an older Zenoh without the key: keep its default
            log.debug("connect/retry not supported", exc_info=True)

    def _declare(self, zenoh: Any) -> None:
        session = self.session
        name = self.graph.graph_name
        deltas = session.declare_subscriber(
            wire.delta_key(name, ALL), zenoh.handlers.FifoChannel(LIMITS.max_waiting_deltas),
            allowed_origin=zenoh.Locality.REMOTE)
        self._entities.append(deltas)
        self.start_receiver(deltas.handler, zenoh.ZError)
        self._entities.append(session.liveliness().declare_subscriber(
            wire.member_key(name, ALL), self._on_member))
        if self.graph.read_only:
            return
        self._publisher = session.declare_publisher(self._delta_key,
                                                    **delta_publisher_options(zenoh))
        self._entities.append(self._publisher)
        self._entities.append(session.declare_queryable(self._state_key, self._on_query,
                                                        complete=True))
        self._token = session.liveliness().declare_token(self._member_key)
        self._entities.append(self._token)

    def close(self) -> None:
        """Detach the graph and close the session (idempotent, safe from any thread)."""
        if self._closed.is_set():
            return
        self._closed.set()
        self.graph.receive_while_polling(None)
        self.graph.attach(None)
        if self.graph.replica is self:
            self.graph.replica = None
        self.anti_entropy.stop()
        session, self.session = self.session, None
        if session is not None:
            with self._writer_keys_lock:
                writer_keys, self._writer_keys = self._writer_keys, {}
            for key_expr in writer_keys.values():
                self._undeclare(session, key_expr)
            for entity in reversed(self._entities):
                try:
                    entity.undeclare()
                except Exception:  # noqa: BLE001 - already gone with the session
                    pass
            try:
                session.close()
            except Exception:
                log.debug("closing Zenoh session failed", exc_info=True)
        receiver = self._receiver
        if receiver is not None:            # its blocking take ended with the session
            receiver.close()
        worker = self._worker
        if worker is not None and worker is not threading.current_thread():
            worker.join(timeout=2.0)

    @property
    def closed(self) -> bool:
        return self._closed.is_set()

    # ------------------------------------------------------------------ outgoing
    def _publish(self, payload: bytes) -> None:
        publisher = self._publisher
        if publisher is None:
            return
        publisher.put(payload)
        self.stats.published += 1

    def seen(self) -> dict[int, int]:
        """This replica's watermarks: own replica -> what it has published."""
        seen = self.members.watermarks()
        graph = self.graph
        seen[graph.replica_id] = graph.published_hlc() if not graph.read_only else 0
        return seen

    def publish_digest(self) -> None:
        """Flush coalesced deltas, then publish this replica's digest on its delta key (after
        every delta it describes: same publisher, so receivers get it in order)."""
        if self._publisher is None or self._closed.is_set():
            return
        self.graph.flush()
        seen = self.seen()
        payload = self.graph.encoder.digest(seen[self.graph.replica_id], seen)
        self._publisher.put(payload)
        self.stats.digests_sent += 1

    # ------------------------------------------------------------------ admission
    def admit_delta(self, key: str, payload: bytes) -> bool:
        """Admit one received delta (or digest) published on `key`: size, decoding,
        validation (dsr/admission.py), write policy, node limits, then merge.  Returns True
        if it was merged (a digest: handled).  Never raises: a refusal is logged and counted
        in `stats` (per reason), and leaves the graph untouched.

        Called on the receiver thread or on the agent's thread polling in dispatch()
        (dsr/receiver.py: one at a time, in arrival order)."""
        self.stats.received += 1
        try:
            if len(payload) > LIMITS.max_delta_bytes:
                self._reject(key, "too_large", f"delta of {len(payload)} bytes, over the limit "
                             f"of {LIMITS.max_delta_bytes} (CHRONAV_DSR_MAX_DELTA_BYTES)")
                return False
            message = wire.decode(payload)
            problem = message_problem(self.graph, message, wire.last_chunk(key), "delta")
            if problem is not None:
                self._reject(key, *problem)
                return False
            if message.kind == "digest":
                self._on_digest(message)
                return True
            if self._checks_deltas:
                problem_text = self.policy.check(message, self.graph)
                if problem_text is not None:
                    self._reject(key, "policy", problem_text)
                    return False
            problem = delta_node_problem(self.graph, message)
            if problem is not None:
                self._reject(key, *problem)
                return False
            graph = self.graph
            if graph.writers.bound_agent(message.replica) is None:
                graph.writers.note(message.replica, message.agent)
            graph.apply_message(message)
            self.members.advance(message.replica, message.top_hlc)
            self.stats.applied += 1
            return True
        except WireError as exc:
            self._reject(key, "invalid", str(exc))
        except Exception:  # never kill the receiving thread or the agent's
            self.stats.errors += 1
            log.exception("DSR %s failed to apply a delta from %s", self.graph.agent, key)
        return False

    def admit_state(self, key: str, payload: bytes) -> bool:
        """Admit one state reply (or part of one) served on `key`: size, decoding, validation,
        screening of relayed claims once joined (dsr/state_trust.py), write policy (a state
        may be kept in part), node limits, then merge.  Returns True if (some of) it was
        merged.  Never raises: one bad reply must not abort the anti-entropy round that
        carries the good ones."""
        try:
            if len(payload) > LIMITS.max_state_bytes:
                self._reject(key, "too_large", f"state of {len(payload)} bytes, over the limit "
                             f"of {LIMITS.max_state_bytes} (CHRONAV_DSR_MAX_STATE_BYTES)")
                return False
            with gc_paused():
                if not self._merge_state(key, wire.decode(payload)):
                    return False
            self.stats.state_merged += 1
            return True
        except WireError as exc:
            self._reject(key, "invalid", str(exc))
        except Exception:
            self.stats.errors += 1
            log.exception("DSR %s failed to merge a state from %s", self.graph.agent, key)
        return False

    def _merge_state(self, key: str, message: wire.Decoded) -> bool:
        graph = self.graph
        problem = message_problem(graph, message, wire.last_chunk(key), "state")
        if problem is not None:
            self._reject(key, *problem)
            return False
        graph.writers.note(message.replica, message.agent)
        live = self.members.live_agents()
        if self.joined:
            message = self._screen(key, message, live)
        kept, text = self.policy.review_state(message, graph)
        if text is not None:    # refused whole (kept is None), or in part
            self._reject(key, "policy", text)
        if kept is None:
            return False
        note_state_writers(graph.writers, graph.agent, message.agent, kept.writers, live,
                           joined=self.joined)
        nodes, problems = within_node_limits(graph, kept.nodes)
        for reason, (first, count) in problems.items():   # one refusal per reason and state
            self._reject(key, reason, first + (f" (and {count - 1} more nodes)" if count > 1
                                               else ""))
        graph.apply_message(wire.Decoded(kept.kind, kept.graph, kept.agent, kept.replica, {},
                                         nodes, kept.edges, kept.top_hlc))
        self.members.note_state(message)
        return True

    def _reject(self, source: str, reason: str, text: str, count: int = 1) -> None:
        stats = self.stats
        if reason == "policy":
            stats.rejected_policy += 1
        else:
            stats.rejected += 1
        stats.rejects[reason] = stats.rejects.get(reason, 0) + count
        stats.last_reject = f"{source}: {text}"
        # One log budget per reason, so that a flood of garbage on the delta keys cannot hide
        # policy violations or forged states from the log.
        show, quiet = self._log_budget.allow(reason)
        if show:
            log.warning("DSR %s dropped message from %s [%s]: %s (%d refused for this reason%s)",
                        self.graph.agent, source, reason, text, stats.rejects[reason],
                        f"; {quiet} not logged since the last line" if quiet else "")

    def _screen(self, key: str, message: wire.Decoded, live: set[str]) -> wire.Decoded:
        from dsr.state_trust import screen_state
        graph = self.graph
        seen, vouched = self.members.trust_snapshot()
        live = live | {graph.agent}
        screened = screen_state(message, local=graph.element_state,
                                binding=graph.writers.bound_agent, live=live, seen=seen,
                                vouched=vouched, me=(graph.agent, graph.replica_id),
                                attributed=graph.writers.writer_agent)
        self.stats.deferred += screened.deferred
        for reason, text in screened.problems:
            self._reject(key, reason, text)
        if screened.about_me:
            self._answer_forgery(message.agent)
        return screened.message

    def _answer_forgery(self, liar: str) -> None:
        """A state forged a claim about this agent: say at once what it really published (a
        digest on its own key: every member that has not merged this agent's own state
        since it (re)started then fetches it, `_on_digest`), so the members that deferred the
        claim learn the truth and refuse it from then on."""
        self.stats.forgeries_about_me += 1
        log.warning("DSR %s: the state of %r forged a claim about %s; publishing a digest",
                    self.graph.agent, liar, self.graph.agent)
        if self._publisher is not None and not self.graph.read_only:
            self.publish_digest()

    # ------------------------------------------------------------------ Zenoh callbacks
    def start_receiver(self, channel: Any, closed_error: type[Exception]) -> None:
        """Handle the deltas of `channel` (a Zenoh channel handler: try_recv() / recv(), which
        raises `closed_error` once closed) from now on: on a receiver thread, or on the
        agent's thread while it polls in dispatch() (dsr/receiver.py)."""
        self._receiver = receiver_of(channel, self._on_delta, self._on_delta_by_agent,
                                     closed_error, name=f"dsr-rx-{self.graph.agent}")
        self._receiver.start()

    def _on_delta(self, sample: Any) -> None:
        self.admit_delta(str(sample.key_expr), sample.payload.to_bytes())

    def _on_delta_by_agent(self, sample: Any) -> None:
        self.admit_delta(str(sample.key_expr), sample.payload.to_bytes())
        self.stats.received_by_agent += 1

    def _on_query(self, query: Any) -> None:
        try:
            if "stats" in str(query.parameters):
                query.reply(self._state_key, orjson.dumps(self.report()),
                            encoding=STATS_ENCODING)
            else:
                with gc_paused():   # encoding a large state makes ~10^5 short-lived objects
                    for part in self.graph.state_parts(self.seen()):
                        query.reply(self._state_key, part, encoding=wire.ENCODING)
                self.stats.state_served += 1
        except Exception:
            self.stats.errors += 1
            log.exception("DSR %s failed to answer a state query", self.graph.agent)

    def _on_member(self, sample: Any) -> None:
        import zenoh
        self.member_seen(wire.last_chunk(str(sample.key_expr)),
                         sample.kind == zenoh.SampleKind.PUT)

    def member_seen(self, agent: str, live: bool) -> None:
        """A member's liveliness token appeared (live) or vanished: update the member table,
        declare or undeclare its delta key, and fetch the state of one that (re)appeared."""
        if agent == self.graph.agent:
            return
        self.members.presence(agent, live)
        self._declare_writer_key(agent, live)
        if live:
            self.anti_entropy.request(agent)

    def report(self) -> dict[str, Any]:
        """What `chronav dsr stats` shows for this member."""
        graph = self.graph
        return {"format": STATS_FORMAT, "agent": graph.agent, "graph": graph.graph_name,
                "replica": graph.replica_id, "nodes": len(graph),
                "tombstones": graph.tombstones(), "stats": self.stats.as_dict(),
                "members": self.members.summary()}

    def _declare_writer_key(self, agent: str, live: bool) -> None:
        """Declare in this session the key a member publishes its deltas on (undeclare it when
        the member leaves).

        Why: deltas arrive through one wildcard subscription (`delta/*`: writers come and go),
        and Zenoh delivers a sample faster when the receiving session has declared its exact
        key (Session.declare_keyexpr; measured: docs/performance.md).  Only an optimisation:
        the wildcard subscription delivers every delta either way."""
        with self._writer_keys_lock:
            session = self.session
            declared = self._writer_keys.get(agent)
            if not live:
                if declared is not None and session is not None:
                    del self._writer_keys[agent]
                    self._undeclare(session, declared)
                return
            if declared is not None or session is None \
                    or len(self._writer_keys) >= MAX_DECLARED_WRITER_KEYS:
                return
            try:
                self._writer_keys[agent] = session.declare_keyexpr(
                    wire.delta_key(self.graph.graph_name, agent))
            except Exception:  # a name Zenoh refuses: the wildcard serves it
                log.debug("DSR %s: cannot declare the delta key of %r", self.graph.agent, agent,
                          exc_info=True)

    @staticmethod
    def _undeclare(session: Any, key_expr: Any) -> None:
        try:
            session.undeclare(key_expr)
        except Exception:  # already gone with the session
            log.debug("undeclaring %s failed", key_expr, exc_info=True)

    # ------------------------------------------------------------------ anti-entropy
    def _on_digest(self, message: wire.Decoded) -> None:
        self.stats.digests_received += 1
        self.graph.writers.note(message.replica, message.agent)
        self.graph.clock.observe(message.clock)
        self.members.advance(message.replica, message.clock)
        targets = self.anti_entropy.lagging(message)
        self.stats.fetches_postponed = self.anti_entropy.postponed
        if targets and not self.graph.read_only:
            self.stats.anti_entropy += 1
            for target in sorted(targets):
                self.anti_entropy.request(target)

    def _initial_sync(self) -> None:
        members = sorted({wire.last_chunk(str(reply.ok.key_expr)) for reply in
                          self.session.liveliness().get(
                              wire.member_key(self.graph.graph_name, ALL),
                              timeout=self.sync_timeout) if reply.ok is not None}
                         - {self.graph.agent})
        for member in members:
            self.members.add(member)
            self._declare_writer_key(member, True)
        self.anti_entropy.join_round(members, self._sync)

    def _sync(self, agent: str) -> int:
        """Fetch and merge the state of one member (or of all, agent == '*'); returns the
        number of state replies merged."""
        import zenoh
        session = self.session
        if session is None:
            return 0
        self.stats.syncs += 1
        merged = self.stats.state_merged
        replies = session.get(wire.state_key(self.graph.graph_name, agent),
                              target=zenoh.QueryTarget.ALL,
                              consolidation=zenoh.ConsolidationMode.NONE,
                              timeout=self.sync_timeout,
                              allowed_destination=zenoh.Locality.REMOTE)
        for reply in replies:
            if reply.ok is not None:
                self.admit_state(str(reply.ok.key_expr), reply.ok.payload.to_bytes())
            else:
                log.warning("DSR %s: state query %s failed: %s", self.graph.agent, agent,
                            reply.err.payload.to_string())
        return self.stats.state_merged - merged

    def sync(self, agent: str = ALL) -> None:
        """Run one anti-entropy round now (blocking)."""
        self._sync(agent)

    def _is_connected(self) -> bool:
        info = self.session.info
        return bool(info.routers_zid() or info.peers_zid())

    def maintain(self) -> None:
        """One round of upkeep: digest out, tombstones compacted (also called by tests).

        A read-only replica publishes no digest (nobody waits for it) but forgets tombstones like
        any member: a watcher that lives all day (the launcher) otherwise kept every removal."""
        if not self.graph.read_only:
            self.publish_digest()
        forgotten = self.graph.compact(self.members.acked)
        self.stats.compacted += forgotten
        self.stats.tombstones = self.graph.tombstones()

    def _work(self, connected: bool) -> None:
        self.anti_entropy.run(self._closed, name=self.graph.agent, connected=self._is_connected,
                              sync=self._sync, maintain=self.maintain,
                              on_error=self._count_error, was_connected=connected,
                              watch_interval=self.watch_interval)

    def _count_error(self) -> None:
        self.stats.errors += 1


@contextmanager
def join(agent: str, graph: str | None = None, settings: ZenohSettings | None = None, *,
         read_only: bool = False, policy: WritePolicy | None = None,
         sync_timeout: float = 10.0, spin: SpinPolicy | None = None) -> Iterator[DSRGraph]:
    """A DSRGraph replicated over Zenoh for the duration of the block.

    On entry the current graph is fetched from the other replicas, so the graph is complete
    when the block starts.  The session is always closed on exit.
    """
    dsr_graph = DSRGraph(agent, graph=graph or graph_name_from_env(), read_only=read_only,
                         spin=spin)
    with Replica(dsr_graph, settings, policy=policy, sync_timeout=sync_timeout):
        yield dsr_graph

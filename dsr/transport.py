"""Replication of a DSRGraph over Zenoh (key space and format: docs/dsr_wire_format.md).

- Local deltas are published on ``chronav/<graph>/delta/<agent>`` (reliable, BLOCK congestion
  control: a CRDT delta must never be silently dropped by a full queue).
- Remote deltas arrive on ``chronav/<graph>/delta/*``; each is validated (schema, claimed agent
  == key, writer ids, clock drift) and checked against the write policy (dsr/policy.py) before
  it touches the graph; state replies too.  Rejected ones are
  logged and counted in `ReplicaStats`, and the graph is untouched.
- State transfer: each writable replica answers ``chronav/<graph>/state/<agent>`` with its full
  CRDT state.  A replica queries ``state/*`` when it starts, and again whenever its connection
  comes back (puts made while disconnected are lost by Zenoh, so this anti-entropy is needed).
- Presence: a liveliness token ``chronav/<graph>/members/<agent>``; when a member (re)appears,
  the others query its state, which carries what it wrote while it was cut off.
"""

from __future__ import annotations

import gc
import logging
import queue
import random
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from typing import Any

from dsr import wire
from dsr.config import ZenohSettings, clean_zenoh_error, graph_name_from_env
from dsr.errors import DSRError, WireError
from dsr.graph import DSRGraph
from dsr.policy import AllowAll, WritePolicy

log = logging.getLogger(__name__)
_ALL = "*"
_LOG_FIRST_REJECTS = 20


class TransportError(DSRError, ConnectionError):
    """The Zenoh session could not be opened (router not reachable, bad endpoint...)."""


@dataclass
class ReplicaStats:
    """Counters of one replica; written by Zenoh callback threads, read by anyone."""

    received: int = 0           # remote delta samples received
    applied: int = 0            # remote deltas merged
    rejected: int = 0           # invalid messages dropped (schema, forged writer, clock...)
    rejected_policy: int = 0    # valid deltas/states refused by the write policy
    published: int = 0          # local deltas published
    state_served: int = 0       # state queries answered
    state_merged: int = 0       # state replies merged
    syncs: int = 0              # anti-entropy rounds (initial join included)
    errors: int = 0             # unexpected exceptions inside callbacks
    last_reject: str = ""

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


class Replica:
    """Binds a DSRGraph to a Zenoh session.  Use `join()` or `with Replica(...) as replica:`."""

    def __init__(self, graph: DSRGraph, settings: ZenohSettings | None = None, *,
                 policy: WritePolicy | None = None, sync_timeout: float = 10.0,
                 watch_interval: float = 0.5, linger_s: float = 0.0003) -> None:
        self.graph = graph
        self.settings = settings or ZenohSettings.from_env()
        self.policy: WritePolicy = policy or AllowAll()
        self.sync_timeout = sync_timeout
        self.watch_interval = watch_interval
        self.linger_s = linger_s
        self.stats = ReplicaStats()
        self._rejects_by_kind: dict[str, int] = {}
        self.session: Any = None
        self._publisher: Any = None
        self._token: Any = None
        self._entities: list[Any] = []
        self._sync_requests: queue.Queue[str | None] = queue.Queue()
        self._worker: threading.Thread | None = None
        self._closed = threading.Event()
        self._connected = False
        name = graph.graph_name
        self._delta_key = wire.delta_key(name, graph.agent)
        self._state_key = wire.state_key(name, graph.agent)
        self._member_key = wire.member_key(name, graph.agent)

    # ------------------------------------------------------------------ lifecycle
    def __enter__(self) -> Replica:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def open(self) -> None:
        """Open the session, declare entities, fetch the current state (blocking)."""
        import zenoh

        conf = self.settings.to_zenoh_config()
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
            self._connected = self._is_connected()
            # Join: one member's complete state is enough to start (merging every member's
            # copy of a large graph would multiply the join time); then a background round
            # merges every other replica's state, which covers deltas that were in flight
            # while the answer was built and anything the first member lacked.
            self._initial_sync()
            self._sync_requests.put(_ALL)
            self._worker = threading.Thread(target=self._work, name=f"dsr-sync-{self.graph.agent}",
                                            daemon=True)
            self._worker.start()
            if not self.graph.read_only:
                self.graph.attach(self._publish, linger_s=self.linger_s)
        except BaseException:
            self.close()
            raise
        self.graph.replica = self

    def _declare(self, zenoh: Any) -> None:
        session = self.session
        name = self.graph.graph_name
        self._entities.append(session.declare_subscriber(
            wire.delta_key(name, _ALL), self._on_delta, allowed_origin=zenoh.Locality.REMOTE))
        self._entities.append(session.liveliness().declare_subscriber(
            wire.member_key(name, _ALL), self._on_member))
        if self.graph.read_only:
            return
        self._publisher = session.declare_publisher(
            self._delta_key, encoding=wire.ENCODING,
            congestion_control=zenoh.CongestionControl.BLOCK,
            reliability=zenoh.Reliability.RELIABLE)
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
        self.graph.attach(None)
        if self.graph.replica is self:
            self.graph.replica = None
        self._sync_requests.put(None)
        session, self.session = self.session, None
        if session is not None:
            for entity in reversed(self._entities):
                try:
                    entity.undeclare()
                except Exception:  # noqa: BLE001, S110 - already gone with the session
                    pass
            try:
                session.close()
            except Exception:  # noqa: BLE001
                log.debug("closing Zenoh session failed", exc_info=True)
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

    # ------------------------------------------------------------------ incoming
    def _reject(self, source: str, reason: str, policy: bool = False) -> None:
        stats = self.stats
        if policy:
            stats.rejected_policy += 1
        else:
            stats.rejected += 1
        stats.last_reject = f"{source}: {reason}"
        # One log budget per kind of refusal, so that a flood of garbage on the delta keys
        # cannot hide policy violations or bad state replies from the log.
        kind = f"{'state' if '/state/' in source else 'delta'}-{'policy' if policy else 'invalid'}"
        seen = self._rejects_by_kind.get(kind, 0) + 1
        self._rejects_by_kind[kind] = seen
        if seen <= _LOG_FIRST_REJECTS or seen % 1000 == 0:
            log.warning("DSR %s dropped message from %s: %s (rejected so far: %d, %d of this "
                        "kind; logging the first %d and every 1000th)", self.graph.agent, source,
                        reason, stats.rejected + stats.rejected_policy, seen, _LOG_FIRST_REJECTS)

    def _problem(self, message: wire.Decoded, claimed: str, kind: str) -> str | None:
        graph = self.graph
        if message.kind != kind:
            return f"a {message.kind!r} message on a {kind} key"
        if message.graph != graph.graph_name:
            return f"message for graph {message.graph!r}, this is {graph.graph_name!r}"
        if message.agent != claimed:
            return f"forged writer: claims agent {message.agent!r} on the key of {claimed!r}"
        if message.replica == graph.replica_id:
            return f"forged writer: uses this replica's id {message.replica}"
        owner = graph.writer_agent(message.replica)
        if owner is not None and owner != message.agent:
            return f"forged writer: replica id {message.replica} belongs to agent {owner!r}"
        if kind == "state":
            for replica, agent in message.writers.items():
                known = graph.writer_agent(int(replica))
                if known is not None and known != agent:
                    return (f"forged writer: state says replica {replica} is {agent!r}, "
                            f"it is {known!r}")
        if kind == "delta":
            if message.writers:
                return "a delta must not carry 'writers'"
            foreign = wire.foreign_writer(message)
            if foreign is not None:
                return f"forged writer: delta of replica {message.replica} carries {foreign}"
        top = message.top_hlc
        if top and graph.clock.too_far_ahead(top):
            return f"clock {top} is too far in the future"
        return None

    def _on_delta(self, sample: Any) -> None:
        self.stats.received += 1
        key = str(sample.key_expr)
        try:
            message = wire.decode(sample.payload.to_bytes())
            problem = self._problem(message, wire.last_chunk(key), "delta")
            if problem is not None:
                self._reject(key, problem)
                return
            problem = self.policy.check(message, self.graph)
            if problem is not None:
                self._reject(key, problem, policy=True)
                return
            self.graph.apply_message(message)
            self.stats.applied += 1
        except WireError as exc:
            self._reject(key, str(exc))
        except Exception:  # noqa: BLE001 - never kill Zenoh's callback thread
            self.stats.errors += 1
            log.exception("DSR %s failed to apply a delta from %s", self.graph.agent, key)

    def _on_query(self, query: Any) -> None:
        try:
            query.reply(self._state_key, self.graph.state_message(), encoding=wire.ENCODING)
            self.stats.state_served += 1
        except Exception:  # noqa: BLE001
            self.stats.errors += 1
            log.exception("DSR %s failed to answer a state query", self.graph.agent)

    def _on_member(self, sample: Any) -> None:
        import zenoh
        agent = wire.last_chunk(str(sample.key_expr))
        if sample.kind == zenoh.SampleKind.PUT and agent != self.graph.agent:
            self._sync_requests.put(agent)

    def _merge_state(self, sample: Any) -> None:
        """Validate, check against the policy, merge.  Never raises: one bad reply must not
        abort the anti-entropy round that carries the good ones."""
        key = str(sample.key_expr)
        try:
            with _gc_paused():
                message = wire.decode(sample.payload.to_bytes())
                problem = self._problem(message, wire.last_chunk(key), "state")
                if problem is not None:
                    self._reject(key, problem)
                    return
                kept, problem = self.policy.review_state(message, self.graph)
                if problem is not None:    # refused whole (kept is None), or in part
                    self._reject(key, problem, policy=True)
                if kept is None:
                    return
                self.graph.apply_message(kept)
            self.stats.state_merged += 1
        except WireError as exc:
            self._reject(key, str(exc))
        except Exception:  # noqa: BLE001
            self.stats.errors += 1
            log.exception("DSR %s failed to merge a state from %s", self.graph.agent, key)

    # ------------------------------------------------------------------ anti-entropy
    def _initial_sync(self) -> None:
        members = sorted({wire.last_chunk(str(reply.ok.key_expr)) for reply in
                          self.session.liveliness().get(
                              wire.member_key(self.graph.graph_name, _ALL),
                              timeout=self.sync_timeout) if reply.ok is not None}
                         - {self.graph.agent})
        random.shuffle(members)          # spread the load when many agents start together
        for member in members:
            if self._sync(member):
                return
        if not members:
            self._sync(_ALL)

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
                self._merge_state(reply.ok)
            else:
                log.warning("DSR %s: state query %s failed: %s", self.graph.agent, agent,
                            reply.err.payload.to_string())
        return self.stats.state_merged - merged

    def sync(self, agent: str = _ALL) -> None:
        """Run one anti-entropy round now (blocking)."""
        self._sync(agent)

    def _is_connected(self) -> bool:
        info = self.session.info
        return bool(info.routers_zid() or info.peers_zid())

    def _work(self) -> None:
        while not self._closed.is_set():
            try:
                agent = self._sync_requests.get(timeout=self.watch_interval)
            except queue.Empty:
                agent = ""
            if agent is None or self._closed.is_set():
                return
            try:
                connected = self._is_connected()
                if connected and not self._connected:
                    log.info("DSR %s: connection back, resynchronising", self.graph.agent)
                    agent = _ALL
                self._connected = connected
                if agent:
                    self._sync(agent)
            except Exception:  # noqa: BLE001 - session closed under us, or a bad reply
                if self._closed.is_set():
                    return
                self.stats.errors += 1
                log.exception("DSR %s: anti-entropy round failed", self.graph.agent)


@contextmanager
def _gc_paused() -> Iterator[None]:
    """Pause the cyclic GC while a whole state is decoded and merged.

    Why: decoding a 10,000-node state allocates ~10^6 small objects, which triggers repeated
    full collections scanning the whole heap (measured: join time x1.7-2.5).  None of these
    objects form cycles, so deferring collection to the end loses nothing."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


@contextmanager
def join(agent: str, graph: str | None = None, settings: ZenohSettings | None = None, *,
         read_only: bool = False, policy: WritePolicy | None = None,
         sync_timeout: float = 10.0) -> Iterator[DSRGraph]:
    """A DSRGraph replicated over Zenoh for the duration of the block.

    On entry the current graph is fetched from the other replicas, so the graph is complete
    when the block starts.  The session is always closed on exit.
    """
    dsr_graph = DSRGraph(agent, graph=graph or graph_name_from_env(), read_only=read_only)
    with Replica(dsr_graph, settings, policy=policy, sync_timeout=sync_timeout):
        yield dsr_graph

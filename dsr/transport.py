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
"""

from __future__ import annotations

import logging
import queue
import random
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
import time
from dataclasses import asdict, dataclass, field
from typing import Any

import orjson

from dsr import wire
from dsr.collector import FREEZE_AFTER_JOIN_NODES, gc_paused, tune_collector
from dsr.config import ZenohSettings, clean_zenoh_error, graph_name_from_env
from dsr.errors import DSRError, WireError
from dsr.graph import DSRGraph
from dsr.limits import LIMITS, node_problem
from dsr.policy import AllowAll, WritePolicy
from dsr.receiver import DeltaReceiver, receiver_of
from dsr.signals import SpinPolicy

log = logging.getLogger(__name__)
_ALL = "*"
#: members whose delta key a session declares (Replica._declare_writer_key); past this many the
#: wildcard subscription still delivers every delta, only without the shortcut
MAX_DECLARED_WRITER_KEYS = 256
_LOG_FIRST_REJECTS = 20
STATS_FORMAT = "chronav-dsr-stats/1"
STATS_ENCODING = "application/json;chronav-dsr-stats/1"


class TransportError(DSRError, ConnectionError):
    """The Zenoh session could not be opened (router not reachable, bad endpoint...)."""


#: reasons a received message (or part of a state) is refused; counted one by one
REASONS = ("invalid", "too_large", "wrong_graph", "wrong_kind", "forged_writer", "forged_stamp",
           "clock_ahead", "removal_receipt", "policy", "too_many_attrs", "node_too_large")


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


def delta_publisher_options(zenoh: Any) -> dict[str, Any]:
    """The options of a replica's delta publisher (docs/dsr_wire_format.md, "Key space")."""
    return {"encoding": wire.ENCODING, "congestion_control": zenoh.CongestionControl.BLOCK,
            "reliability": zenoh.Reliability.RELIABLE}


class _LogBudget:
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


class Replica:
    """Binds a DSRGraph to a Zenoh session.  Use `join()` or `with Replica(...) as replica:`."""

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
        #: how often a digest is published, tombstones compacted and lags checked
        self.digest_interval = digest_interval
        #: a member that left still counts for tombstone compaction this long (a partitioned
        #: member must not come back with elements everybody else forgot)
        self.member_retention_s = member_retention_s
        #: how long a member must hold writes we lack before we fetch a state for them
        self.lag_grace_s = 4 * digest_interval
        #: longest pause between two digest-triggered state fetches of one member
        self.max_fetch_backoff_s = 30.0
        #: member -> (no digest-triggered fetch before, pause after the next one, last fetch)
        self._fetch_backoff: dict[str, tuple[float, float, float]] = {}
        #: monotonic clock of the anti-entropy timers (tests replace it)
        self._now: Callable[[], float] = time.monotonic
        self.stats = ReplicaStats()
        self._log_budget = _LogBudget()
        self.session: Any = None
        self._publisher: Any = None
        self._token: Any = None
        self._entities: list[Any] = []
        self._sync_requests: queue.Queue[str | None] = queue.Queue()
        self._worker: threading.Thread | None = None
        self._closed = threading.Event()
        self._connected = False
        self._joined = False
        self._table_lock = threading.Lock()
        #: takes received deltas off the Zenoh channel (dsr/receiver.py; None until opened)
        self._receiver: DeltaReceiver | None = None
        #: seen[z]: this replica holds every write replica z stamped up to seen[z].  A running
        #: writer's entry is set only by its own state and then moved on by its own deltas and
        #: digests (see _advance); without an entry its relayed writes wait for it (deferred)
        self._seen: dict[int, int] = {}
        #: agents whose own state (this incarnation) has been merged: their replica ids known
        self._vouched: set[str] = set()
        self._pending_syncs: set[str] = set()
        #: writers the `seen` of the last state merged covers (completeness of a join's copy)
        self._state_cover = 0
        self._members: dict[str, Member] = {}
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
            self._connected = self._is_connected()
            # Join: one member's complete state is enough to start (merging every member's
            # copy of a large graph would multiply the join time); then a background round
            # merges every other replica's state, which covers deltas that were in flight
            # while the answer was built and anything the first member lacked.
            with gc_paused(freeze_if=lambda: len(self.graph) >= FREEZE_AFTER_JOIN_NODES):
                self._initial_sync()
            self._joined = True
            self._sync_requests.put(_ALL)
            if not self.graph.read_only:
                self.graph.attach(self._publish, linger_s=self.linger_s)
            self.graph.receive_while_polling(self._receiver)
            self._worker = threading.Thread(target=self._work, name=f"dsr-sync-{self.graph.agent}",
                                            daemon=True)
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
        except Exception:  # noqa: BLE001 - an older Zenoh without the key: keep its default
            log.debug("connect/retry not supported", exc_info=True)

    def _declare(self, zenoh: Any) -> None:
        session = self.session
        name = self.graph.graph_name
        deltas = session.declare_subscriber(
            wire.delta_key(name, _ALL), zenoh.handlers.FifoChannel(LIMITS.max_waiting_deltas),
            allowed_origin=zenoh.Locality.REMOTE)
        self._entities.append(deltas)
        self.start_receiver(deltas.handler, zenoh.ZError)
        self._entities.append(session.liveliness().declare_subscriber(
            wire.member_key(name, _ALL), self._on_member))
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
        self._sync_requests.put(None)
        session, self.session = self.session, None
        if session is not None:
            with self._writer_keys_lock:
                writer_keys, self._writer_keys = self._writer_keys, {}
            for key_expr in writer_keys.values():
                self._undeclare(session, key_expr)
            for entity in reversed(self._entities):
                try:
                    entity.undeclare()
                except Exception:  # noqa: BLE001, S110 - already gone with the session
                    pass
            try:
                session.close()
            except Exception:  # noqa: BLE001
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
        with self._table_lock:
            seen = dict(self._seen)
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
        payload = self.graph._encoder.digest(seen[self.graph.replica_id], seen)
        self._publisher.put(payload)
        self.stats.digests_sent += 1

    # ------------------------------------------------------------------ incoming
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

    def _problem(self, message: wire.Decoded, claimed: str, kind: str) -> tuple[str, str] | None:
        graph = self.graph
        if message.kind != kind and not (kind == "delta" and message.kind == "digest"):
            return "wrong_kind", f"a {message.kind!r} message on a {kind} key"
        if message.graph != graph.graph_name:
            return "wrong_graph", (f"message for graph {message.graph!r}, this is "
                                   f"{graph.graph_name!r}")
        if message.agent != claimed:
            return "forged_writer", (f"forged writer: claims agent {message.agent!r} on the "
                                     f"key of {claimed!r}")
        if message.replica == graph.replica_id:
            return "forged_writer", f"forged writer: uses this replica's id {message.replica}"
        owner = graph.bound_agent(message.replica)
        if owner is not None and owner != message.agent:
            return "forged_writer", (f"forged writer: replica id {message.replica} belongs to "
                                     f"agent {owner!r}")
        if kind == "state":
            for replica, agent in message.writers.items():
                known = graph.bound_agent(int(replica))
                if known is not None and known != agent:
                    return "forged_writer", (f"forged writer: state says replica {replica} is "
                                             f"{agent!r}, it is {known!r}")
        else:
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
            else:                       # attribute updates only (the hot path)
                own = message.replica
                for _, state in message.nodes:
                    for attr, reg in state.attrs.items():
                        if reg[1] != own:
                            return "forged_writer", (
                                f"forged writer: delta of replica {own} carries attribute "
                                f"{attr!r} written by replica {reg[1]}")
        if kind == "state":
            removal = wire.removal_problem(message)
            if removal is not None:
                return "removal_receipt", removal
        top = message.top_hlc
        if top and graph.clock.too_far_ahead(top):
            return "clock_ahead", (f"clock {top} is more than {graph.clock.max_offset_ms} ms "
                                   "ahead of this replica's wall clock")
        return None

    def start_receiver(self, channel: Any, closed_error: type[Exception]) -> None:
        """Handle the deltas of `channel` (a Zenoh channel handler: try_recv() / recv(), which
        raises `closed_error` once closed) from now on: on a receiver thread, or on the
        agent's thread while it polls in dispatch() (dsr/receiver.py)."""
        self._receiver = receiver_of(channel, self._on_delta, self._on_delta_by_agent,
                                     closed_error, name=f"dsr-rx-{self.graph.agent}")
        self._receiver.start()

    def _on_delta_by_agent(self, sample: Any) -> None:
        self._on_delta(sample)
        self.stats.received_by_agent += 1

    def _on_delta(self, sample: Any) -> None:
        """Handle one received delta (or digest), on the receiver thread or on the agent's
        thread polling in dispatch() (dsr/receiver.py: one at a time, in arrival order)."""
        self.stats.received += 1
        key = "?"
        try:
            key = str(sample.key_expr)
            payload = sample.payload.to_bytes()
            if len(payload) > LIMITS.max_delta_bytes:
                self._reject(key, "too_large", f"delta of {len(payload)} bytes, over the limit "
                             f"of {LIMITS.max_delta_bytes} (CHRONAV_DSR_MAX_DELTA_BYTES)")
                return
            message = wire.decode(payload)
            problem = self._problem(message, wire.last_chunk(key), "delta")
            if problem is not None:
                self._reject(key, *problem)
                return
            if message.kind == "digest":
                self._on_digest(message)
                return
            if self._checks_deltas:
                problem_text = self.policy.check(message, self.graph)
                if problem_text is not None:
                    self._reject(key, "policy", problem_text)
                    return
            graph = self.graph
            held = graph._nodes.get
            for node_id, state in message.nodes:     # node limits (dsr/limits.py)
                attrs = state.attrs
                if not attrs:
                    continue
                current = held(node_id)
                if current is not None:             # scalars over existing keys: cannot grow
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
                    self._reject(key, *problem)
                    return
            if graph._bound.get(message.replica) is None:
                graph.note_writer(message.replica, message.agent)
            graph.apply_message(message)
            self._advance(message.replica, message.top_hlc)
            self.stats.applied += 1
        except WireError as exc:
            self._reject(key, "invalid", str(exc))
        except Exception:  # noqa: BLE001 - never kill the receiving thread or the agent's
            self.stats.errors += 1
            log.exception("DSR %s failed to apply a delta from %s", self.graph.agent, key)

    def _advance(self, replica: int, hlc: int) -> None:
        """A writer's own messages arrive in order: we now hold all it stamped up to hlc, if
        we held all it stamped before the first of them that reached us.  Only its own state
        proves that (it sets the entry, `_note_seen`): a subscription takes effect at the
        router a moment after it is declared, a broken session loses the puts made meanwhile,
        and in both cases the deltas that do arrive come in order after a hole.  So without an
        entry, nothing is advanced."""
        with self._table_lock:
            seen = self._seen
            current = seen.get(replica)
            if current is not None and hlc > current:
                seen[replica] = hlc

    def _gap(self, agent: str | None) -> None:
        """Deltas of `agent` (None: of everybody) may have been lost: forget its watermarks
        until its own state has been merged again.  Caller holds _table_lock."""
        me = self.graph.replica_id
        for replica, owner in list(self.graph._bound.items()):
            if replica != me and (agent is None or owner == agent):
                self._seen.pop(replica, None)

    def _on_digest(self, message: wire.Decoded) -> None:
        self.stats.digests_received += 1
        self.graph.note_writer(message.replica, message.agent)
        self.graph.clock.observe(message.clock)
        self._advance(message.replica, message.clock)
        lagging = False
        with self._table_lock:
            member = self._members.get(message.agent)
            if member is None or member.replica != message.replica:
                member = self._members[message.agent] = Member(message.agent, message.replica)
            member.clock, member.seen, member.live = message.clock, message.seen, True
            mine = self.graph.replica_id
            # Anti-entropy: the member holds writes we lack.  Deltas in flight, or a backlog
            # on a loaded machine, look the same for a while: only a lag that lasts
            # lag_grace_s (and at most once per lag_grace_s per writer) fetches a state.
            now = self._now()
            since = member.behind
            for replica, hlc in message.seen.items():
                if replica != mine and hlc > self._seen.get(replica, 0) and replica not in since:
                    since[replica] = (hlc, now)
            targets: set[str] = set()
            if message.agent not in self._vouched:
                # its own state (this incarnation) is not merged here yet: until it is, its
                # watermark and its replica ids are unknown here and claims about it are
                # deferred; fetch it now (also how a member answers a forged claim about it)
                targets.add(message.agent)
            for replica, (hlc, at) in list(since.items()):
                if self._seen.get(replica, 0) >= hlc:
                    del since[replica]
                elif now - at >= self.lag_grace_s:
                    # fetch from the writer itself if it runs (only its own state is
                    # trusted for its writes), else from the member that holds them
                    owner = self.graph.bound_agent(replica)
                    known = self._members.get(owner) if owner is not None else None
                    targets.add(owner if known is not None and known.live
                                else message.agent)   # type: ignore[arg-type]
                    since[replica] = (message.seen.get(replica, hlc), now)
            targets = {t for t in targets if self._fetch_allowed(t, now)}
            lagging = bool(targets)
        if lagging and not self.graph.read_only:
            self.stats.anti_entropy += 1
            for target in sorted(targets):
                self._request_sync(target)

    def _fetch_allowed(self, target: str, now: float) -> bool:
        """Rate limit of the state fetches digests ask for, per member: the first at once,
        the next ones after a pause that doubles (lag_grace_s, 2x, 4x ... up to
        max_fetch_backoff_s) as long as digests keep asking (a member whose state is
        refused, or that keeps announcing writes its state does not carry; or this replica
        is so loaded that it lags behind its own queue of deltas: fetching a state then
        makes it slower still).  The pause starts again from lag_grace_s only after a quiet
        period of twice the longest pause.  So a member costs one fetch per change it makes
        (a lost delta), and at most one per max_fetch_backoff_s when something keeps them
        coming.  Caller holds _table_lock."""
        base, longest = self.lag_grace_s, self.max_fetch_backoff_s
        not_before, pause, last = self._fetch_backoff.get(target, (0.0, base, -2 * longest))
        if now < not_before:
            self.stats.fetches_postponed += 1
            return False
        if now - last >= 2 * longest:
            pause = base
        self._fetch_backoff[target] = (now + pause, min(2 * pause, longest), now)
        return True

    def _request_sync(self, agent: str) -> None:
        """Queue a state fetch, once: digests of several members may point at the same one."""
        with self._table_lock:
            if agent in self._pending_syncs:
                return
            self._pending_syncs.add(agent)
        self._sync_requests.put(agent)

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
        except Exception:  # noqa: BLE001
            self.stats.errors += 1
            log.exception("DSR %s failed to answer a state query", self.graph.agent)

    def report(self) -> dict[str, Any]:
        """What `chronav dsr stats` shows for this member."""
        graph = self.graph
        with self._table_lock:
            members = {m.agent: {"replica": m.replica, "live": m.live} for m in
                       self._members.values()}
        return {"format": STATS_FORMAT, "agent": graph.agent, "graph": graph.graph_name,
                "replica": graph.replica_id, "nodes": len(graph),
                "tombstones": graph.tombstones(), "stats": self.stats.as_dict(),
                "members": members}

    def _on_member(self, sample: Any) -> None:
        import zenoh
        agent = wire.last_chunk(str(sample.key_expr))
        if agent == self.graph.agent:
            return
        live = sample.kind == zenoh.SampleKind.PUT
        with self._table_lock:
            member = self._members.get(agent)
            if member is None:
                member = self._members[agent] = Member(agent)
            member.live = live
            member.gone_at = 0.0 if live else time.monotonic()
            # either way its stream may have a gap (a broken session loses puts): until its
            # own state is merged again, its watermarks and replica ids are not trusted
            self._gap(agent)
            self._vouched.discard(agent)
        self._declare_writer_key(agent, live)
        if live:
            self._request_sync(agent)

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
            except Exception:  # noqa: BLE001 - a name Zenoh refuses: the wildcard serves it
                log.debug("DSR %s: cannot declare the delta key of %r", self.graph.agent, agent,
                          exc_info=True)

    @staticmethod
    def _undeclare(session: Any, key_expr: Any) -> None:
        try:
            session.undeclare(key_expr)
        except Exception:  # noqa: BLE001 - already gone with the session
            log.debug("undeclaring %s failed", key_expr, exc_info=True)

    def live_agents(self) -> set[str]:
        with self._table_lock:
            return {m.agent for m in self._members.values() if m.live}

    def acked(self, replica: int, hlc: int) -> bool:
        """Every member (running, or gone less than member_retention_s ago) has told us, in
        its digest, that it holds every write of `replica` up to `hlc`."""
        now = time.monotonic()
        with self._table_lock:
            for member in self._members.values():
                if not member.live and now - member.gone_at > self.member_retention_s:
                    continue
                if member.seen.get(replica, 0) < hlc:
                    return False
        return True

    def _merge_state(self, sample: Any) -> None:
        """Validate, screen, check against the policy, merge.  Never raises: one bad reply
        must not abort the anti-entropy round that carries the good ones."""
        key = str(sample.key_expr)
        try:
            payload = sample.payload.to_bytes()
            if len(payload) > LIMITS.max_state_bytes:
                self._reject(key, "too_large", f"state of {len(payload)} bytes, over the limit "
                             f"of {LIMITS.max_state_bytes} (CHRONAV_DSR_MAX_STATE_BYTES)")
                return
            with gc_paused():
                message = wire.decode(payload)
                problem = self._problem(message, wire.last_chunk(key), "state")
                if problem is not None:
                    self._reject(key, *problem)
                    return
                self.graph.note_writer(message.replica, message.agent)
                live = self.live_agents()
                if self._joined:
                    message = self._screen(key, message, live)
                kept, text = self.policy.review_state(message, self.graph)
                if text is not None:    # refused whole (kept is None), or in part
                    self._reject(key, "policy", text)
                if kept is None:
                    return
                self._note_writers(message.agent, kept.writers, live)
                self.graph.apply_message(wire.Decoded(
                    kept.kind, kept.graph, kept.agent, kept.replica, {},
                    self._within_node_limits(key, kept.nodes), kept.edges, kept.top_hlc))
                self._note_seen(message)
            self.stats.state_merged += 1
        except WireError as exc:
            self._reject(key, "invalid", str(exc))
        except Exception:  # noqa: BLE001
            self.stats.errors += 1
            log.exception("DSR %s failed to merge a state from %s", self.graph.agent, key)

    def _within_node_limits(self, key: str, nodes: list[tuple[int, Any]]) -> list[tuple[int, Any]]:
        """A state's node entries minus those that would take a node over the node limits
        (dsr/limits.py); counted once per reason and state (saying how many nodes)."""
        held = self.graph.element_state
        kept = []
        problems: dict[str, tuple[str, int]] = {}
        for node_id, state in nodes:
            if state.attrs:
                current = held("node", node_id)
                problem = node_problem(node_id, current.attrs if current is not None else None,
                                       state.attrs, registers=True)
                if problem is not None:
                    first, count = problems.get(problem[0], (problem[1], 0))
                    problems[problem[0]] = (first, count + 1)
                    continue
            kept.append((node_id, state))
        for reason, (text, count) in problems.items():   # one refusal per reason and state
            self._reject(key, reason, text + (f" (and {count - 1} more nodes)" if count > 1
                                              else ""))
        return kept

    def _note_writers(self, sender: str, writers: dict[str, str], live: set[str]) -> None:
        """Which `writers` entries of a merged state this replica takes as its own knowledge
        (and will serve in its state replies: DSRGraph.served_writers), and which only to
        attribute relayed writes (dsr/state_trust.py):
        - the sender's own replica ids (an agent vouches for its incarnations): proven (after
          the join, the screening has removed every entry naming this replica's own agent
          that it does not know: state_trust.screen_state);
        - every entry of the first state of a join: nothing to check it against, trusted
          (documented limit; its sender served only what it could prove).  Entries about
          running agents included: a joiner that left them out would relay their writes
          without attribution to the next joiner, whose policy would refuse them;
        - after the join, an entry about an agent that is not running: attribution only, never
          served (a relay proves nothing); about a running agent: nothing (deferred until that
          agent's own messages or state say it)."""
        graph = self.graph
        me = graph.agent
        for key, agent in writers.items():
            replica = int(key)
            if graph.bound_agent(replica) is not None:
                continue
            if agent == sender or agent == me or not self._joined:
                graph.note_writer(replica, agent)
            elif agent not in live:
                graph.note_relayed_writer(replica, agent)

    def _note_seen(self, message: wire.Decoded) -> None:
        """After merging a state: we now hold what its sender held of its own writes, and of
        the writes of agents that are not running.  A running writer's watermark comes only
        from its own state, even in the first state of a join: its relayed stamps may have
        been screened out, and deltas it published while our subscription was taking effect
        may be missing here though the relay holds them (`_advance`)."""
        sender = message.agent
        live = self.live_agents()
        graph = self.graph
        with self._table_lock:
            if message.clock:                   # the last part of the state: all merged
                self._vouched.add(sender)
                self._state_cover = len(message.seen)
            for replica, hlc in message.seen.items():
                owner = graph.bound_agent(replica) or message.writers.get(str(replica))
                own = replica == message.replica or owner == sender
                if not own and owner in live:
                    continue    # a running writer: only its own state sets its watermark
                if hlc >= self._seen.get(replica, 0):   # (one that is not running sends
                    self._seen[replica] = hlc          # nothing more: a relay's is true)

    def _screen(self, key: str, message: wire.Decoded, live: set[str]) -> wire.Decoded:
        from dsr.state_trust import screen_state
        graph = self.graph
        with self._table_lock:
            seen = dict(self._seen)
            vouched = set(self._vouched)
        live = live | {graph.agent}
        screened = screen_state(message, local=graph.element_state, binding=graph.bound_agent,
                                live=live, seen=seen, vouched=vouched,
                                me=(graph.agent, graph.replica_id),
                                attributed=graph.writer_agent)
        self.stats.deferred += screened.deferred
        for reason, text in screened.problems:
            self._reject(key, reason, text)
        if screened.about_me:
            self._answer_forgery(message.agent)
        return screened.message

    def _answer_forgery(self, liar: str) -> None:
        """A state forged a claim about this agent: say at once what it really published (a
        digest on its own key: every member that has not merged this agent's own state
        since it (re)started then fetches it, dsr/transport.py `_on_digest`), so the
        members that deferred the claim learn the truth and refuse it from then on."""
        self.stats.forgeries_about_me += 1
        log.warning("DSR %s: the state of %r forged a claim about %s; publishing a digest",
                    self.graph.agent, liar, self.graph.agent)
        if self._publisher is not None and not self.graph.read_only:
            self.publish_digest()

    # ------------------------------------------------------------------ anti-entropy
    def _initial_sync(self) -> None:
        members = sorted({wire.last_chunk(str(reply.ok.key_expr)) for reply in
                          self.session.liveliness().get(
                              wire.member_key(self.graph.graph_name, _ALL),
                              timeout=self.sync_timeout) if reply.ok is not None}
                         - {self.graph.agent})
        with self._table_lock:
            for member in members:
                self._members.setdefault(member, Member(member))
        for member in members:
            self._declare_writer_key(member, True)
        random.shuffle(members)          # spread the load when many agents start together
        for member in members:
            # a member whose state covers every running member (its `seen` has as many
            # writers) is a complete copy; a tool that serves only its own writes is not:
            # merge it and go on (docs/dsr_wire_format.md, "Writing as a foreign client")
            self._state_cover = 0
            if self._sync(member) and self._state_cover >= len(members):
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

    def maintain(self) -> None:
        """One round of upkeep: digest out, tombstones compacted (also called by tests)."""
        if self.graph.read_only:
            return
        self.publish_digest()
        forgotten = self.graph.compact(self.acked)
        self.stats.compacted += forgotten
        self.stats.tombstones = self.graph.tombstones()

    def _work(self) -> None:
        next_digest = time.monotonic()
        while not self._closed.is_set():
            timeout = max(0.0, min(self.watch_interval, next_digest - time.monotonic()))
            try:
                agent = self._sync_requests.get(timeout=timeout)
            except queue.Empty:
                agent = ""
            if agent is None or self._closed.is_set():
                return
            if agent:
                with self._table_lock:
                    self._pending_syncs.discard(agent)
            try:
                connected = self._is_connected()
                if connected and not self._connected:
                    log.info("DSR %s: connection back, resynchronising", self.graph.agent)
                    with self._table_lock:   # deltas were lost meanwhile: watermarks are void
                        self._gap(None)
                    agent = _ALL
                self._connected = connected
                if agent:
                    self._sync(agent)
                if time.monotonic() >= next_digest:
                    next_digest = time.monotonic() + self.digest_interval
                    if connected:
                        self.maintain()
            except Exception:  # noqa: BLE001 - session closed under us, or a bad reply
                if self._closed.is_set():
                    return
                self.stats.errors += 1
                log.exception("DSR %s: anti-entropy round failed", self.graph.agent)


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

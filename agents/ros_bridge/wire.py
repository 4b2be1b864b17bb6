"""rmw_zenoh's conventions, so that ROS 2 nodes on the same Zenoh router see chronav as a ROS 2 node.

Why written here (and nothing else of ROS): rmw_zenoh has no Python binding and ROS 2 cannot be
installed where chronav runs; its conventions are small and documented (ros2/rmw_zenoh,
docs/design.md), so chronav follows them with its own Zenoh session:

- **data keys** ``<domain>/<topic without leading />/<pkg>::msg::dds_::<Name>_/<RIHS01 hash>``:
  a subscriber of another type or type version never matches;
- **payload**: the message in CDR with its encapsulation header (types.py, rosbags);
- **attachment** of every sample: int64 sequence number, int64 source timestamp (ns since the
  epoch), uint8 GID length (16), the 16-byte publisher GID, all little endian;
- **liveliness tokens** under ``@ros2_lv`` for the node (``NN``) and every publisher (``MP``)
  and subscription (``MS``), carrying namespace, node, mangled topic (``/`` -> ``%``), type,
  hash and the QoS in rmw_zenoh's compact form, which is what ``ros2 node list`` and
  ``ros2 topic list/info`` read;
- **TRANSIENT_LOCAL** publishers are Zenoh advanced publishers with a cache of ``depth`` samples
  and publisher detection (late-joining subscribers such as RViz query it), RELIABLE ones with
  sporadic miss-detection heartbeats, as rmw_zenoh declares them; congestion control is DROP
  unless the history is KEEP_ALL (BLOCK), also as rmw_zenoh does.
"""

from __future__ import annotations

import hashlib
import itertools
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import zenoh
from zenoh import ext

from agents.ros_bridge.types import dds_type_name, serialize, type_hash

ADMIN_SPACE = "@ros2_lv"
GID_SIZE = 16
#: rmw_zenoh's default history depth (QoS::default_qos): a depth equal to it is left out of the token
RMW_ZENOH_DEFAULT_DEPTH = 42
#: rmw_zenoh's sporadic heartbeat period for RELIABLE + TRANSIENT_LOCAL publishers (s)
MISS_DETECTION_HEARTBEAT_S = 0.5
#: largest message the bridge decodes from the ROS side (goals, odometry, scans are far smaller;
#: inbox.py refuses larger ones)
MAX_RECEIVED_BYTES = 4 * 1024 * 1024

Reliability = Literal["reliable", "best_effort"]
Durability = Literal["volatile", "transient_local"]
History = Literal["keep_last", "keep_all"]
# rmw/types.h enum values, as rmw_zenoh writes them in tokens
_RELIABILITY = {"reliable": 1, "best_effort": 2}
_DURABILITY = {"transient_local": 1, "volatile": 2}
_HISTORY = {"keep_last": 1, "keep_all": 2}


@dataclass(frozen=True)
class Qos:
    """The QoS settings that change anything over Zenoh (deadline, lifespan: unimplemented in rmw_zenoh)."""

    reliability: Reliability = "reliable"
    durability: Durability = "volatile"
    depth: int = 10
    history: History = "keep_last"

    def token(self) -> str:
        """rmw_zenoh's ``qos_to_keyexpr``: fields equal to its default QoS (reliable, volatile,
        keep_last, depth 42, infinite deadline/lifespan, automatic liveliness) are left empty."""
        rel = "" if self.reliability == "reliable" else str(_RELIABILITY[self.reliability])
        dur = "" if self.durability == "volatile" else str(_DURABILITY[self.durability])
        hist = "" if self.history == "keep_last" else str(_HISTORY[self.history])
        depth = "" if self.depth == RMW_ZENOH_DEFAULT_DEPTH else str(self.depth)
        return f"{rel}:{dur}:{hist},{depth}:,:,:,,"


def mangle(name: str) -> str:
    """rmw_zenoh's mangled name: every ``/`` becomes ``%`` (an empty name is ``%``)."""
    return name.replace("/", "%") if name else "%"


def fully_qualified(topic: str, namespace: str = "/") -> str:
    """``/ns/topic`` for a relative topic, the topic itself when absolute."""
    if topic.startswith("/"):
        return topic
    return f"{namespace.rstrip('/')}/{topic}" if namespace != "/" else f"/{topic}"


def topic_key(domain: int, topic: str, type_name: str) -> str:
    """The data key expression of ``topic`` (absolute ROS name) with ``type_name`` (pkg/msg/Name)."""
    return f"{domain}/{topic.strip('/')}/{dds_type_name(type_name)}/{type_hash(type_name)}"


def attachment(sequence: int, stamp_ns: int, gid: bytes) -> bytes:
    """The attachment rmw_zenoh puts on every published sample."""
    return struct.pack("<qqB", sequence, stamp_ns, len(gid)) + gid


def parse_attachment(data: bytes) -> tuple[int, int, bytes]:
    """(sequence, stamp in ns, gid) of an rmw_zenoh attachment; ValueError when malformed."""
    if len(data) < 17:
        raise ValueError(f"attachment of {len(data)} bytes, expected at least 17")
    sequence, stamp_ns, size = struct.unpack_from("<qqB", data)
    if len(data) != 17 + size:
        raise ValueError(f"attachment says a {size}-byte GID but carries {len(data) - 17}")
    return sequence, stamp_ns, bytes(data[17:])


def gid_of(key: str) -> bytes:
    """A 16-byte GID unique to an entity (rmw_zenoh derives it from the entity's identity too)."""
    return hashlib.sha256(key.encode()).digest()[:GID_SIZE]


def time_ns() -> int:
    return time.time_ns()


@dataclass
class RosPublisher:
    """One ROS 2 publisher: its key, token, GID and sequence numbers."""

    topic: str
    type_name: str
    qos: Qos
    key: str
    gid: bytes
    _publisher: Any
    _token: Any
    _sequence: itertools.count
    _lock: threading.Lock

    def publish(self, message: Any) -> int:
        """Serialise and put ``message``; returns the CDR size in bytes."""
        return self.publish_cdr(serialize(message, self.type_name))

    def publish_cdr(self, data: bytes) -> int:
        with self._lock:
            seq = next(self._sequence)
        self._publisher.put(data, attachment=attachment(seq, time_ns(), self.gid))
        return len(data)

    def undeclare(self) -> None:
        for entity in (self._token, self._publisher):
            try:
                entity.undeclare()
            except zenoh.ZError:
                pass


class RosNode:
    """A ROS 2 node on a Zenoh session: declares itself, its publishers and subscriptions as
    rmw_zenoh does.  The session is the caller's (opened and closed by it)."""

    def __init__(self, session: zenoh.Session, name: str, domain: int = 0, namespace: str = "/") -> None:
        self.session = session
        self.name = name
        self.domain = domain
        self.namespace = namespace
        self.zid = str(session.info.zid())
        self._entities = itertools.count(1)
        self.node_id = 0
        self._node_prefix = f"{ADMIN_SPACE}/{domain}/{self.zid}/{self.node_id}"
        self._node_suffix = f"%/{mangle(namespace.strip('/') and namespace)}/{name}"
        self._token = session.liveliness().declare_token(f"{self._node_prefix}/{self.node_id}/NN/{self._node_suffix}")
        self.publishers: list[RosPublisher] = []
        self._subscribers: list[tuple[Any, Any]] = []

    def _entity_token(self, kind: str, topic: str, type_name: str, qos: Qos) -> tuple[str, int]:
        entity_id = next(self._entities)
        key = (f"{self._node_prefix}/{entity_id}/{kind}/{self._node_suffix}/{mangle(topic)}/"
               f"{dds_type_name(type_name)}/{type_hash(type_name)}/{qos.token()}")
        return key, entity_id

    def create_publisher(self, topic: str, type_name: str, qos: Qos) -> RosPublisher:
        topic = fully_qualified(topic, self.namespace)
        key = topic_key(self.domain, topic, type_name)
        token_key, _ = self._entity_token("MP", topic, type_name, qos)
        reliable = qos.reliability == "reliable"
        options: dict[str, Any] = {
            "congestion_control": (zenoh.CongestionControl.BLOCK if reliable and qos.history == "keep_all"
                                   else zenoh.CongestionControl.DROP),
            "reliability": zenoh.Reliability.RELIABLE if reliable else zenoh.Reliability.BEST_EFFORT,
        }
        if qos.durability == "transient_local":
            options["cache"] = ext.CacheConfig(max(1, qos.depth))
            options["publisher_detection"] = True
            if reliable:
                options["sample_miss_detection"] = ext.MissDetectionConfig(
                    heartbeat=None, sporadic_heartbeat=MISS_DETECTION_HEARTBEAT_S)
        publisher = ext.declare_advanced_publisher(self.session, key, **options)
        token = self.session.liveliness().declare_token(token_key)
        pub = RosPublisher(topic, type_name, qos, key, gid_of(token_key), publisher, token, itertools.count(1),
                           threading.Lock())
        self.publishers.append(pub)
        return pub

    def create_subscription(self, topic: str, type_name: str, qos: Qos, on_payload: Callable[[bytes], None]) -> None:
        """Hand every sample's payload (CDR bytes, undecoded) of ``topic`` to ``on_payload``, on
        Zenoh's callback thread.  Decoding and checking are the receiver's (inbox.py), so that
        every received byte takes one path that counts what it refuses."""
        topic = fully_qualified(topic, self.namespace)
        key = topic_key(self.domain, topic, type_name)
        token_key, _ = self._entity_token("MS", topic, type_name, qos)

        def on_sample(sample: zenoh.Sample) -> None:
            on_payload(sample.payload.to_bytes())

        sub: ext.AdvancedSubscriber[None] | zenoh.Subscriber[None]
        if qos.durability == "transient_local":
            sub = ext.declare_advanced_subscriber(self.session, key, on_sample,
                                                  history=ext.HistoryConfig(detect_late_publishers=True,
                                                                            max_samples=max(1, qos.depth)))
        else:
            sub = self.session.declare_subscriber(key, on_sample)
        token = self.session.liveliness().declare_token(token_key)
        self._subscribers.append((sub, token))

    def close(self) -> None:
        """Undeclare everything (tokens first, so ROS tools see the node leave)."""
        for sub, token in self._subscribers:
            for entity in (token, sub):
                try:
                    entity.undeclare()
                except zenoh.ZError:
                    pass
        for pub in self.publishers:
            pub.undeclare()
        try:
            self._token.undeclare()
        except zenoh.ZError:
            pass


def ros_session_config(endpoint: str, mode: str = "client") -> zenoh.Config:
    """A Zenoh session towards the ROS 2 side's router (rmw_zenohd listens on tcp/localhost:7447):
    no multicast scouting, as rmw_zenoh's default configuration."""
    config = zenoh.Config()
    config.insert_json5("mode", f'"{mode}"')
    config.insert_json5("connect/endpoints", f'["{endpoint}"]')
    config.insert_json5("scouting/multicast/enabled", "false")
    if mode != "router":
        config.insert_json5("listen/endpoints", "[]" if mode == "client" else '["tcp/127.0.0.1:0"]')
    return config

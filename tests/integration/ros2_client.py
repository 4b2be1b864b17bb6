"""An independent ROS-2-over-Zenoh client for the tests: rosbags for CDR and type hashes, Zenoh
for transport, and rmw_zenoh's conventions re-built here from its design document
(ros2/rmw_zenoh docs/design.md), NOT from chronav's agents/ros_bridge, so a test that passes
shows chronav follows the documented conventions rather than agreeing with itself.

- data key  ``<domain>/<fully qualified name without leading slash>/<pkg>::msg::dds_::<Name>_/<RIHS01>``
- attachment  ``<q sequence><q timestamp ns><B gid length><gid>`` little endian
- tokens  ``@ros2_lv/<domain>/<zid>/<node id>/<entity id>/<NN|MP|MS>/<enclave %>/<namespace %>/<node>[/...]``
"""

from __future__ import annotations

import hashlib
import struct
import threading
import time
from pathlib import Path
from typing import Any

import zenoh
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from zenoh import ext

EXTRA = {
    # wg-perception/people (ros2 branch) and ros-navigation/navigation2, transcribed here
    "people_msgs/msg/Person": "string name\ngeometry_msgs/Point position\ngeometry_msgs/Point velocity\n"
                              "float64 reliability\nstring[] tagnames\nstring[] tags\n",
    "people_msgs/msg/People": "std_msgs/Header header\npeople_msgs/Person[] people\n",
    "nav2_msgs/msg/CostmapFilterInfo": "std_msgs/Header header\nuint8 type\nstring filter_mask_topic\n"
                                       "float32 base\nfloat32 multiplier\n",
}
STORE = get_typestore(Stores.ROS2_JAZZY)
for _name, _text in EXTRA.items():
    STORE.register(get_types_from_msg(_text, _name))


def dds(type_name: str) -> str:
    pkg, kind, name = type_name.split("/")
    return f"{pkg}::{kind}::dds_::{name}_"


def data_key(domain: int, topic: str, type_name: str) -> str:
    return f"{domain}/{topic.lstrip('/')}/{dds(type_name)}/{STORE.hash_rihs01(type_name)}"


class Received:
    """Messages of one subscription, decoded, with their attachments."""

    def __init__(self, type_name: str) -> None:
        self.type_name = type_name
        self.messages: list[Any] = []
        self.attachments: list[tuple[int, int, bytes]] = []
        self.errors: list[str] = []
        self.lock = threading.Lock()

    def __call__(self, sample: zenoh.Sample) -> None:
        try:
            msg = STORE.deserialize_cdr(sample.payload.to_bytes(), self.type_name)
            raw = sample.attachment.to_bytes() if sample.attachment is not None else b""
            seq, stamp, size = struct.unpack_from("<qqB", raw)
            gid = raw[17:17 + size]
            assert len(raw) == 17 + size
        except Exception as exc:  # noqa: BLE001 - recorded for the test to report
            with self.lock:
                self.errors.append(repr(exc))
            return
        with self.lock:
            self.messages.append(msg)
            self.attachments.append((seq, stamp, gid))

    def last(self) -> Any:
        with self.lock:
            return self.messages[-1] if self.messages else None

    def wait(self, predicate: Any = lambda m: True, timeout: float = 60.0) -> Any:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self.lock:
                for msg in reversed(self.messages):
                    if predicate(msg):
                        return msg
            time.sleep(0.05)
        raise TimeoutError(f"no {self.type_name} matching in {timeout} s ({len(self.messages)} received, "
                           f"errors {self.errors[:3]})")


class Ros2Client:
    """A ROS 2 'node' speaking rmw_zenoh's conventions through its own client session."""

    def __init__(self, endpoint: str, domain: int, node: str = "probe") -> None:
        conf = zenoh.Config()
        conf.insert_json5("mode", '"client"')
        conf.insert_json5("connect/endpoints", f'["{endpoint}"]')
        conf.insert_json5("scouting/multicast/enabled", "false")
        self.session = zenoh.open(conf)
        self.domain = domain
        self.node = node
        self.zid = str(self.session.info.zid())
        self._ids = iter(range(1, 10_000))
        self._keep: list[Any] = []
        self._tokens = [self.session.liveliness().declare_token(f"@ros2_lv/{domain}/{self.zid}/0/0/NN/%/%/{node}")]
        self._seq = iter(range(1, 10**9))

    def _token(self, kind: str, topic: str, type_name: str, qos: str) -> str:
        key = (f"@ros2_lv/{self.domain}/{self.zid}/0/{next(self._ids)}/{kind}/%/%/{self.node}/"
               f"{topic.replace('/', '%')}/{dds(type_name)}/{STORE.hash_rihs01(type_name)}/{qos}")
        self._tokens.append(self.session.liveliness().declare_token(key))
        return key

    def subscribe(self, topic: str, type_name: str, transient_local: bool = False) -> Received:
        received = Received(type_name)
        key = data_key(self.domain, topic, type_name)
        if transient_local:
            sub = ext.declare_advanced_subscriber(self.session, key, received,
                                                  history=ext.HistoryConfig(detect_late_publishers=True))
            self._token("MS", topic, type_name, ":1:,1:,:,:,,")
        else:
            sub = self.session.declare_subscriber(key, received)
            self._token("MS", topic, type_name, "::,10:,:,:,,")
        self._keep.append(sub)
        return received

    def publisher(self, topic: str, type_name: str) -> Any:
        token = self._token("MP", topic, type_name, "::,10:,:,:,,")
        gid = hashlib.md5(token.encode()).digest()
        pub = self.session.declare_publisher(data_key(self.domain, topic, type_name))
        self._keep.append(pub)

        def publish(message: Any) -> None:
            payload = bytes(STORE.serialize_cdr(message, type_name))
            pub.put(payload, attachment=struct.pack("<qqB", next(self._seq), time.time_ns(), 16) + gid)
        publish.matched = lambda: pub.matching_status.matching  # type: ignore[attr-defined]
        return publish

    def graph(self, timeout: float = 2.0) -> list[str]:
        """Every ``@ros2_lv`` token of the domain, as rmw_zenoh's graph cache queries them."""
        replies = self.session.liveliness().get(f"@ros2_lv/{self.domain}/**", timeout=timeout)
        return sorted(str(r.ok.key_expr) for r in replies if r.ok)

    def close(self) -> None:
        for entity in [*self._tokens, *self._keep]:
            try:
                entity.undeclare()
            except zenoh.ZError:
                pass
        self.session.close()


def read_back(path: Path) -> dict[str, list]:
    """Every message of the bag, decoded by rosbags (types from the bag's own definitions) and
    checked against the mcap library's decoder; topic -> [(log time ns, message)]."""
    out: dict[str, list] = {}
    with AnyReader([path]) as reader:
        for conn, log_ns, raw in reader.messages():
            out.setdefault(conn.topic, []).append((log_ns, reader.deserialize(raw, conn.msgtype)))
    with path.open("rb") as handle:
        decoded = list(make_reader(handle, decoder_factories=[DecoderFactory()]).iter_decoded_messages())
    assert len(decoded) == sum(len(v) for v in out.values())
    assert {schema.name for schema, *_ in decoded} >= {"nav_msgs/msg/Odometry", "people_msgs/msg/People"}
    return out

"""`chronav ros stats`: what the ROS 2 bridge received and refused, read from ROS 2's /diagnostics.

Why from /diagnostics (and not from the DSR): the counts concern the ROS side (messages a ROS
network sent), the bridge already publishes them there for ROS tools (rqt_robot_monitor,
`ros2 topic echo /diagnostics`), and one source means `chronav ros stats` and a ROS engineer see
the same numbers.  The command joins the ROS side's router as a ROS 2 node of its own
(``chronav_stats``) and waits for the bridge's next DiagnosticArray (it publishes one a second).
With ``--run RUN`` it reads the counts the run kept instead (``<run>/ros_received.json``, written
by the bridge as they change and at its end): no ROS network needed, and a finished run works.
"""

from __future__ import annotations

import json
import threading
from pathlib import Path
from typing import Any

from agents.ros_bridge import messages as msgs
from agents.ros_bridge.config import BridgeConfig
from agents.ros_bridge.types import deserialize

STATUS_PREFIX = ": received "


class NoDiagnostics(Exception):
    """No DiagnosticArray of the bridge arrived in time."""


def counts_of(array: Any, node: str) -> dict[str, dict[str, Any]]:
    """{topic: {"taken": n, "refused": n, "reasons": {reason: n}, "level": 0|1}} of the bridge
    ``node``'s statuses in one DiagnosticArray (other nodes' statuses are skipped)."""
    out: dict[str, dict[str, Any]] = {}
    prefix = f"{node}{STATUS_PREFIX}"
    for status in array.status:
        if not status.name.startswith(prefix):
            continue
        values = {kv.key: kv.value for kv in status.values}
        out[status.name[len(prefix):]] = {
            "taken": int(values.get("taken", 0)), "refused": int(values.get("refused", 0)),
            "reasons": {k.split(".", 1)[1]: int(v) for k, v in values.items() if k.startswith("refused.")},
            "level": int(status.level)}
    return out


def read_stats(cfg: BridgeConfig, timeout_s: float) -> dict[str, Any]:
    """The bridge's counts from its next /diagnostics on the ROS side of ``cfg``."""
    import zenoh

    from agents.ros_bridge.wire import RosNode, ros_session_config

    got: dict[str, Any] = {}
    arrived = threading.Event()

    def on_payload(data: bytes) -> None:
        try:
            counts = counts_of(deserialize(data, msgs.DIAGNOSTIC_ARRAY), cfg.node)
        except Exception:  # noqa: BLE001 - another node's malformed array is not ours to report
            return
        if counts and not arrived.is_set():
            got.update(counts)
            arrived.set()

    try:
        session = zenoh.open(ros_session_config(cfg.endpoint, cfg.mode))
    except zenoh.ZError:
        raise NoDiagnostics(f"the ROS 2 side's Zenoh router at {cfg.endpoint} does not answer; give its endpoint "
                            "with --ros-endpoint or CHRONAV_ROS_ENDPOINT") from None
    try:
        node = RosNode(session, f"{cfg.node}_stats", cfg.domain, cfg.namespace)
        spec = cfg.topics.diagnostics
        node.create_subscription(spec.name, msgs.DIAGNOSTIC_ARRAY, spec.qos.qos(), on_payload)
        arrived.wait(timeout_s)
        node.close()
    finally:
        session.close()
    if not got:
        raise NoDiagnostics(f"no {cfg.topics.diagnostics.name} from ROS 2 node /{cfg.node} on domain {cfg.domain} "
                            f"via {cfg.endpoint} within {timeout_s:g} s: is the bridge running (chronav launch "
                            "--ros, chronav ros bridge), and are the domain and endpoint right?")
    return {"node": cfg.node, "domain": cfg.domain, "topics": got}


#: largest ros_received.json read (a few topics and reasons: a few hundred bytes)
MAX_RECEIVED_FILE_BYTES = 1024 * 1024


def stats_of_run(run_dir: Path) -> dict[str, Any]:
    """The counts a run kept (``<run>/ros_received.json``), in read_stats' shape."""
    from agents.ros_bridge.agent import RECEIVED_FILE
    from scenes.errors import SourceError
    from scenes.files import read_text_bounded

    path = run_dir / RECEIVED_FILE
    if not path.exists():
        raise NoDiagnostics(f"{path} does not exist: the run had no ROS 2 bridge (chronav launch --ros, --robot ros), "
                            "or its bridge received nothing yet")
    try:
        data = json.loads(read_text_bounded(path, max_bytes=MAX_RECEIVED_FILE_BYTES, what="counts file"))
        accepted, refused = data["accepted"], data["refused"]
        topics = {str(t): {"taken": int(accepted.get(t, 0)), "refused": sum(int(n) for n in refused.get(t, {}).values()),
                           "reasons": {str(r): int(n) for r, n in refused.get(t, {}).items()}}
                  for t in sorted(set(accepted) | set(refused))}
        return {"node": str(data.get("node", "chronav")), "run": str(run_dir), "topics": topics}
    except SourceError as exc:
        raise NoDiagnostics(str(exc)) from None
    except (ValueError, KeyError, TypeError, AttributeError, RecursionError) as exc:
        raise NoDiagnostics(f"{path}: not the counts the bridge writes ({type(exc).__name__}: {str(exc)[:80]})") \
            from None

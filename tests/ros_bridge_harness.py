"""The ROS 2 bridge agent without a ROS network: its real setup, step and receive path, with the
Zenoh node replaced by one that records what is published and keeps each subscription's payload
handler (what Zenoh's callback calls for every sample).

Shared by tests/unit/test_ros_bridge_agent.py and tests/unit/test_ros_fuzz.py."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from agents.ros_bridge.agent import RosBridgeAgent
from agents.ros_bridge.types import deserialize, serialize
from agents.runtime.checked_graph import CheckedGraph
from agents.runtime.config import AgentConfig
from agents.runtime.recording import Recorder
from agents.world.offline import graph_at
from agents.world.scene_world import load_world
from tests.support import REPO_ROOT

SCENE = REPO_ROOT / "tests" / "data" / "ros_lounge.yaml"


@dataclass
class FakePublisher:
    topic: str
    type_name: str
    sent: list[Any] = field(default_factory=list)

    def publish(self, message: Any) -> int:
        data = serialize(message, self.type_name)      # what goes on the wire, decoded back
        self.sent.append(deserialize(data, self.type_name))
        return len(data)


class FakeNode:
    def __init__(self) -> None:
        self.publishers: dict[str, FakePublisher] = {}
        self.handlers: dict[str, Any] = {}

    def create_publisher(self, topic: str, type_name: str, qos: Any) -> FakePublisher:
        self.publishers[topic] = FakePublisher(topic, type_name)
        return self.publishers[topic]

    def create_subscription(self, topic: str, type_name: str, qos: Any, on_payload: Any) -> None:
        self.handlers[topic] = on_payload

    def close(self) -> None:
        pass


class OfflineBridge(RosBridgeAgent):
    """RosBridgeAgent whose ROS side is a FakeNode (no Zenoh session)."""

    def _connect(self) -> FakeNode:  # type: ignore[override]
        self.session = type("Session", (), {"close": lambda _self: None})()
        return FakeNode()


def bridge(robot: str = "ros", t_s: float = 36_000.0) -> tuple[OfflineBridge, Any]:
    """A bridge on a DSR of the ros_lounge scene at ``t_s`` (10:00), set up (not stepped yet)."""
    world = load_world(SCENE)
    graph = graph_at(world, t_s)
    agent = OfflineBridge(AgentConfig(name="ros_bridge", scene=SCENE, options={"robot": robot}))
    checked = CheckedGraph(graph, "ros_bridge")   # as run_agent gives it: writes outside the vocabulary refused
    agent.setup(checked, Recorder("ros_bridge", None, None))
    return agent, graph

"""What the bridge publishes and subscribes, under which names, frames and QoS (YAML-configurable).

Defaults follow REP-105 (``map`` -> ``odom`` -> ``base_link``) and Nav2's topics and QoS: maps
and filter masks RELIABLE + TRANSIENT_LOCAL depth 1 (a late RViz gets the last one, as from
Nav2's map_server), ``/scan`` as sensor data (BEST_EFFORT, depth 5), ``/tf`` depth 100 as tf2's
broadcaster.  A YAML file (``-o ros_config=FILE`` or ``CHRONAV_ROS_CONFIG``) overrides any of
it; an unknown key or a bad value is an error naming the file and the key.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from agents.ros_bridge.wire import Qos

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"   # where rmw_zenohd listens by default


class QosSpec(BaseModel):
    model_config = ConfigDict(extra="forbid")

    reliability: Literal["reliable", "best_effort"] = "reliable"
    durability: Literal["volatile", "transient_local"] = "volatile"
    depth: int = Field(10, ge=1, le=10_000)

    def qos(self) -> Qos:
        return Qos(self.reliability, self.durability, self.depth)


class TopicSpec(BaseModel):
    model_config = ConfigDict(extra="forbid")

    name: str = Field(pattern=r"^/?[A-Za-z][A-Za-z0-9_/]*$")
    qos: QosSpec = QosSpec()
    enabled: bool = True
    rate_hz: float | None = Field(None, gt=0, le=1000, description="publication rate limit (None: on change)")


def _latched(name: str, check_hz: float | None = 1.0) -> TopicSpec:
    """A TRANSIENT_LOCAL depth-1 topic published on change (checked ``check_hz`` times a second)."""
    return TopicSpec(name=name, qos=QosSpec(durability="transient_local", depth=1), rate_hz=check_hz)


class Topics(BaseModel):
    model_config = ConfigDict(extra="forbid")

    map: TopicSpec = _latched("/map")
    social_costmap: TopicSpec = TopicSpec(name="/social_costmap", qos=QosSpec(durability="transient_local", depth=1),
                                          rate_hz=5.0)
    keepout_filter_mask: TopicSpec = TopicSpec(name="/keepout_filter_mask",
                                               qos=QosSpec(durability="transient_local", depth=1), rate_hz=5.0)
    costmap_filter_info: TopicSpec = _latched("/costmap_filter_info", None)
    people: TopicSpec = TopicSpec(name="/people", rate_hz=10.0)
    plan: TopicSpec = TopicSpec(name="/plan", qos=QosSpec(depth=1))
    tf: TopicSpec = TopicSpec(name="/tf", qos=QosSpec(depth=100), rate_hz=20.0)
    odom: TopicSpec = TopicSpec(name="/odom", rate_hz=20.0)
    scan: TopicSpec = TopicSpec(name="/scan", qos=QosSpec(reliability="best_effort", depth=5), rate_hz=10.0)
    agenda: TopicSpec = _latched("/agenda")
    clock: TopicSpec = TopicSpec(name="/clock", qos=QosSpec(reliability="best_effort", depth=1), rate_hz=20.0)
    goal_pose: TopicSpec = TopicSpec(name="/goal_pose")
    cmd_vel: TopicSpec = TopicSpec(name="/cmd_vel")
    #: what the bridge received and refused, per subscribed topic (diagnostic_msgs/DiagnosticArray;
    #: ROS nodes publish their health there about once a second, as diagnostic_updater does)
    diagnostics: TopicSpec = TopicSpec(name="/diagnostics", rate_hz=1.0)


class Frames(BaseModel):
    model_config = ConfigDict(extra="forbid")

    map: str = "map"
    odom: str = "odom"
    base: str = "base_link"
    laser: str = "base_link"
    person_prefix: str = "person/"


class BridgeConfig(BaseModel):
    """The ROS side: router endpoint, domain, node name, topics and frames."""

    model_config = ConfigDict(extra="forbid")

    endpoint: str = Field(DEFAULT_ENDPOINT, description="the ROS 2 side's Zenoh router (rmw_zenohd)")
    mode: Literal["client", "peer"] = "client"
    domain: int = Field(0, ge=0, le=232, description="ROS_DOMAIN_ID")
    node: str = Field("chronav", pattern=r"^[A-Za-z][A-Za-z0-9_]*$")
    namespace: str = Field("/", pattern=r"^/([A-Za-z][A-Za-z0-9_/]*)?$")
    topics: Topics = Topics()
    frames: Frames = Frames()


class BridgeConfigError(ValueError):
    """The bridge's YAML is unreadable or has a bad key or value."""


def _merge(base: dict[str, object], extra: dict[str, object]) -> dict[str, object]:
    """``extra`` over ``base``, mapping by mapping (a topic's ``rate_hz`` alone keeps its name and QoS)."""
    out = dict(base)
    for key, value in extra.items():
        old = out.get(key)
        out[key] = _merge(old, value) if isinstance(old, dict) and isinstance(value, dict) else value
    return out


def load_bridge_config(path: Path | None = None, **overrides: object) -> BridgeConfig:
    """Defaults, then the YAML file (if any), then ``overrides`` (command-line options)."""
    data: dict[str, object] = {}
    if path is not None:
        try:
            loaded = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
        except (OSError, yaml.YAMLError) as exc:
            raise BridgeConfigError(f"{path}: cannot read it as YAML ({exc})") from None
        if loaded is not None and not isinstance(loaded, dict):
            raise BridgeConfigError(f"{path}: expected a mapping of settings (endpoint, domain, topics, frames)")
        data.update(loaded or {})
    data.update({k: v for k, v in overrides.items() if v is not None})
    try:
        return BridgeConfig.model_validate(_merge(BridgeConfig().model_dump(), data))
    except ValidationError as exc:
        where = path or "ros bridge settings"
        problems = "; ".join(f"{'.'.join(str(p) for p in e['loc'])}: {e['msg']}" for e in exc.errors())
        raise BridgeConfigError(f"{where}: {problems}") from None


def config_from_options(options: dict[str, str]) -> BridgeConfig:
    """The agent's ``-o`` options (``ros_config``, ``ros_endpoint``, ``ros_domain``) and environment
    (``CHRONAV_ROS_CONFIG``, ``CHRONAV_ROS_ENDPOINT``, ``ROS_DOMAIN_ID``)."""
    path = options.get("ros_config") or os.environ.get("CHRONAV_ROS_CONFIG")
    domain = options.get("ros_domain") or os.environ.get("ROS_DOMAIN_ID")
    endpoint = options.get("ros_endpoint") or os.environ.get("CHRONAV_ROS_ENDPOINT")
    try:
        domain_value = None if domain in (None, "") else int(domain)
    except ValueError:
        raise BridgeConfigError(f"ROS domain {domain!r}: give a number from 0 to 232") from None
    return load_bridge_config(Path(path) if path else None, domain=domain_value, endpoint=endpoint)

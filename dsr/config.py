"""Zenoh settings for DSR replicas: loopback by default, explicit endpoints, multicast off.

Why explicit: Zenoh's defaults bind every interface and scout with multicast; on a shared CI box
or a care-centre network we only talk to endpoints we were given.  Several machines join one
graph by pointing CHRONAV_ZENOH_CONNECT at a router they can all reach, or by a json5 Zenoh
config file (CHRONAV_ZENOH_CONFIG) for anything else (TLS, auth, ACL).

Precedence: built-in defaults < config file < environment variables / explicit fields.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, StringConstraints, ValidationError

from dsr.errors import ConfigError
from dsr.model import check_agent_name

if TYPE_CHECKING:
    import zenoh

ENV_CONNECT = "CHRONAV_ZENOH_CONNECT"
ENV_LISTEN = "CHRONAV_ZENOH_LISTEN"
ENV_MODE = "CHRONAV_ZENOH_MODE"
ENV_CONFIG = "CHRONAV_ZENOH_CONFIG"
ENV_MULTICAST = "CHRONAV_ZENOH_MULTICAST"
ENV_GRAPH = "CHRONAV_GRAPH"
DEFAULT_ROUTER = "tcp/127.0.0.1:7447"
DEFAULT_GRAPH = "chronav"

#: "<protocol>/<address>", e.g. tcp/127.0.0.1:7447, tcp/[::1]:7447, tls/host:7447
Endpoint = Annotated[str, StringConstraints(pattern=r"^[a-z][a-z0-9+\-]*/\S+$")]


class ZenohSettings(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)
    mode: Literal["client", "peer", "router"] = "client"
    connect: list[Endpoint] = Field(default_factory=lambda: [DEFAULT_ROUTER])
    listen: list[Endpoint] = Field(default_factory=list)
    multicast: bool = False
    #: link lease: a frozen or partitioned member is declared gone after ~this long
    lease_ms: int = Field(default=2000, ge=100, le=600_000)
    config_file: Path | None = None

    @classmethod
    def from_env(cls, environ: Mapping[str, str] | None = None) -> ZenohSettings:
        """Settings from CHRONAV_ZENOH_* variables; errors name the variable."""
        env = os.environ if environ is None else environ
        fields: dict[str, object] = {}
        sources: dict[str, str] = {}
        if env.get(ENV_MODE):
            fields["mode"] = env[ENV_MODE].strip()
            sources["mode"] = ENV_MODE
        for name, var in (("connect", ENV_CONNECT), ("listen", ENV_LISTEN)):
            if env.get(var) is not None and env.get(var, "").strip() != "":
                fields[name] = [e.strip() for e in env[var].split(",") if e.strip()]
                sources[name] = var
        if env.get(ENV_MULTICAST):
            value = env[ENV_MULTICAST].strip().lower()
            if value not in ("0", "1", "true", "false", "yes", "no"):
                raise ConfigError(f"{ENV_MULTICAST}={env[ENV_MULTICAST]!r}: expected 0 or 1")
            fields["multicast"] = value in ("1", "true", "yes")
        if env.get(ENV_CONFIG):
            path = Path(env[ENV_CONFIG])
            if not path.is_file():
                raise ConfigError(f"{ENV_CONFIG}={env[ENV_CONFIG]!r}: no such file")
            fields["config_file"] = path
            sources["config_file"] = ENV_CONFIG
        try:
            return cls(**fields)
        except ValidationError as exc:
            first = exc.errors()[0]
            name = str(first["loc"][0]) if first["loc"] else ""
            var = sources.get(name, name)
            raise ConfigError(f"{var}: {first['msg']} (got {first.get('input')!r})") from None

    def to_zenoh_config(self) -> zenoh.Config:
        """Build the zenoh.Config; a config file is the base, explicit fields override it."""
        import zenoh

        explicit = set(self.model_fields_set)
        if self.config_file is not None:
            try:
                conf = zenoh.Config.from_file(str(self.config_file))
            except Exception as exc:  # noqa: BLE001 - zenoh raises its own ZError
                raise ConfigError(f"{self.config_file}: invalid Zenoh config: {exc}") from None
        else:
            conf = zenoh.Config()
            explicit |= {"mode", "connect", "listen", "lease_ms"}
        listen = list(self.listen)
        if self.mode == "router" and not listen and "listen" in explicit:
            listen = [DEFAULT_ROUTER]
        connect = list(self.connect)
        if self.mode == "router" and "connect" not in self.model_fields_set:
            connect = []
        try:
            if "mode" in explicit:
                conf.insert_json5("mode", _json(self.mode))
            if "connect" in explicit:
                conf.insert_json5("connect/endpoints", _json(connect))
            if "listen" in explicit:
                conf.insert_json5("listen/endpoints", _json(listen))
            if "lease_ms" in explicit:
                conf.insert_json5("transport/link/tx/lease", str(self.lease_ms))
            conf.insert_json5("scouting/multicast/enabled", _json(self.multicast))
        except Exception as exc:  # noqa: BLE001
            raise ConfigError(f"invalid Zenoh settings {self.describe()}: {exc}") from None
        return conf

    def describe(self) -> str:
        parts = [f"mode={self.mode}"]
        if self.connect and self.mode != "router":
            parts.append("connect=" + ",".join(self.connect))
        if self.listen:
            parts.append("listen=" + ",".join(self.listen))
        if self.config_file:
            parts.append(f"config={self.config_file}")
        return " ".join(parts)


def _json(value: object) -> str:
    import json
    return json.dumps(value)


def graph_name_from_env(environ: Mapping[str, str] | None = None) -> str:
    env = os.environ if environ is None else environ
    name = env.get(ENV_GRAPH) or DEFAULT_GRAPH
    try:
        return check_agent_name(name, "graph")
    except ValueError as exc:
        raise ConfigError(f"{ENV_GRAPH}: {exc}") from None

"""Zenoh settings for DSR replicas and routers: loopback by default, explicit endpoints, no multicast.

Why explicit: Zenoh's defaults bind every interface and scout with multicast; on a shared CI box
or a care-centre network we only talk to endpoints we were given.  Several machines join one
graph by pointing CHRONAV_ZENOH_CONNECT at a router they can all reach; authentication
(user/password, TLS certificates) and the router's access-control list come from the variables
below or from a json5 Zenoh config file (CHRONAV_ZENOH_CONFIG).  docs/deployment.md has a worked
example with the files of deploy/.

Precedence: built-in defaults < config file < environment variables / explicit fields.
Multicast scouting is always set explicitly (off unless asked for).
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import (AfterValidator, BaseModel, ConfigDict, Field, SecretStr, ValidationError,
                      field_validator, model_validator)

from dsr.errors import ConfigError
from dsr.model import check_agent_name

if TYPE_CHECKING:
    import zenoh

ENV_CONNECT = "CHRONAV_ZENOH_CONNECT"
ENV_LISTEN = "CHRONAV_ZENOH_LISTEN"
ENV_MODE = "CHRONAV_ZENOH_MODE"
ENV_CONFIG = "CHRONAV_ZENOH_CONFIG"
ENV_MULTICAST = "CHRONAV_ZENOH_MULTICAST"
ENV_SHARED_MEMORY = "CHRONAV_ZENOH_SHARED_MEMORY"
ENV_LEASE = "CHRONAV_ZENOH_LEASE_MS"
ENV_USER = "CHRONAV_ZENOH_USER"
ENV_PASSWORD = "CHRONAV_ZENOH_PASSWORD"  # a variable name, not a secret
ENV_PASSWORD_FILE = "CHRONAV_ZENOH_PASSWORD_FILE"
ENV_CREDENTIALS = "CHRONAV_ZENOH_CREDENTIALS"
ENV_ACL = "CHRONAV_ZENOH_ACL"
ENV_TLS_ROOT_CA = "CHRONAV_ZENOH_TLS_ROOT_CA"
ENV_TLS_CERT = "CHRONAV_ZENOH_TLS_CERT"
ENV_TLS_KEY = "CHRONAV_ZENOH_TLS_KEY"
ENV_MTLS = "CHRONAV_ZENOH_MTLS"
ENV_GRAPH = "CHRONAV_GRAPH"
DEFAULT_ROUTER = "tcp/127.0.0.1:7447"
DEFAULT_GRAPH = "chronav"

ENDPOINT_FORM = "PROTOCOL/HOST:PORT, e.g. tcp/127.0.0.1:7447"
#: protocols whose address is HOST:PORT (the others, e.g. unixsock-stream/PATH, are passed as given)
_HOST_PORT_PROTOCOLS = ("tcp", "udp", "tls", "quic", "ws")
_ENDPOINT = re.compile(r"^(?P<protocol>[a-z][a-z0-9+\-]*)/(?P<address>[^\s?#]+)(?P<extra>[?#]\S*)?$")
_HOST_PORT = re.compile(r"^(?P<host>\[[0-9A-Fa-f:.]+\]|[^\s:\[\]/]+):(?P<port>[0-9]{1,5})$")
_RUST_SOURCE = re.compile(r"\s+at\s+\S+\.rs:\d+(?::\d+)?\.?")


def check_endpoint(text: str) -> str:
    """A Zenoh endpoint as a person types it, or ConfigError saying the expected form.

    Why our own check: Zenoh accepts a malformed endpoint at configuration time and fails only
    when opening, with a generic "Unable to connect"; pydantic's pattern error quotes a regex."""
    match = _ENDPOINT.match(text.strip()) if isinstance(text, str) else None
    if match is None:
        raise ConfigError(f"{text!r} is not an endpoint; expected {ENDPOINT_FORM}")
    protocol, address = match["protocol"], match["address"]
    if protocol in _HOST_PORT_PROTOCOLS:
        host_port = _HOST_PORT.match(address)
        if host_port is None:
            raise ConfigError(f"{text!r}: expected {protocol}/HOST:PORT, e.g. {protocol}/127.0.0.1:7447")
        if not 1 <= int(host_port["port"]) <= 65535:
            raise ConfigError(f"{text!r}: port {host_port['port']} is not between 1 and 65535")
    return text.strip()


def _endpoint(text: str) -> str:
    try:
        return check_endpoint(text)
    except ConfigError as exc:
        raise ValueError(str(exc)) from None


#: "<protocol>/<address>", e.g. tcp/127.0.0.1:7447, tcp/[::1]:7447, tls/host:7447
Endpoint = Annotated[str, AfterValidator(_endpoint)]


def clean_zenoh_error(error: object) -> str:
    """Zenoh's message without the Rust source location it appends (`at /root/.cargo/...rs:447`):
    the path means nothing to a user and changes with every Zenoh build."""
    return _RUST_SOURCE.sub("", str(error)).strip().rstrip(".!") or "failed"

#: settings field -> environment variable holding a file path (checked to exist)
_PATH_VARS = {"config_file": ENV_CONFIG, "credentials_file": ENV_CREDENTIALS, "acl_file": ENV_ACL,
              "tls_root_ca": ENV_TLS_ROOT_CA, "tls_certificate": ENV_TLS_CERT,
              "tls_private_key": ENV_TLS_KEY}
_BOOL_VARS = {"multicast": ENV_MULTICAST, "mtls": ENV_MTLS, "shared_memory": ENV_SHARED_MEMORY}
_TRUE, _FALSE = ("1", "true", "yes", "on"), ("0", "false", "no", "off")


class ZenohSettings(BaseModel):
    """How one process reaches the others: mode, endpoints, lease, credentials, TLS, ACL."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    mode: Literal["client", "peer", "router"] = "client"
    connect: list[Endpoint] = Field(default_factory=lambda: [DEFAULT_ROUTER])
    listen: list[Endpoint] = Field(default_factory=list)
    multicast: bool = False
    #: Zenoh's shared-memory transport (on in Zenoh's own defaults).  Off: a DSR delta is a few
    #: kB and goes through the socket as fast, while with it on every process that sends one
    #: over 3 kB gets a 16 MB pool in /dev/shm that every process it talks to maps, about 100 MB
    #: of each agent's RSS in a run (docs/long_runs.md, "RSS is not all the agent's own")
    shared_memory: bool = False
    #: link lease: a frozen or partitioned member is declared gone after ~this long
    lease_ms: int = Field(default=2000, ge=100, le=600_000)
    config_file: Path | None = None
    #: usrpwd authentication: this process's identity (clients; a router only when it connects
    #: to another router)
    user: str | None = Field(default=None, min_length=1, pattern=r"^[^\s:]+$")
    password: SecretStr | None = None
    #: router: the usrpwd dictionary, one "user:password" per line
    credentials_file: Path | None = None
    #: router: a json5 file holding {access_control: {...}} (Zenoh ACL: rules, subjects, policies)
    acl_file: Path | None = None
    #: TLS (tls/ endpoints): the CA that signed the router's certificate; this process's own
    #: certificate and key (a router's server certificate, or a client's for mutual TLS)
    tls_root_ca: Path | None = None
    tls_certificate: Path | None = None
    tls_private_key: Path | None = None
    mtls: bool = False
    #: bound on the Zenoh handshake when opening a link, in ms; None = Zenoh's default (10 s:
    #: a listener that is not a Zenoh router holds a client that long)
    open_timeout_ms: int | None = Field(default=None, ge=1, le=3_600_000)

    @field_validator("config_file", "credentials_file", "acl_file", "tls_root_ca",
                     "tls_certificate", "tls_private_key")
    @classmethod
    def _file_exists(cls, path: Path | None) -> Path | None:
        if path is not None and not path.is_file():
            raise ValueError(f"no such file: {str(path)!r}")
        return path

    @model_validator(mode="after")
    def _pairs(self) -> ZenohSettings:
        if (self.user is None) != (self.password is None):
            raise ValueError("user and password go together (set both or neither)")
        if (self.tls_certificate is None) != (self.tls_private_key is None):
            raise ValueError("tls_certificate and tls_private_key go together")
        if self.mtls and (self.tls_certificate is None or self.tls_root_ca is None):
            raise ValueError("mutual TLS needs tls_root_ca, tls_certificate and tls_private_key")
        return self

    @classmethod
    def from_env(cls, environ: Mapping[str, str] | None = None) -> ZenohSettings:
        """Settings from CHRONAV_ZENOH_* variables; errors name the variable."""
        env = os.environ if environ is None else environ
        fields, sources = _fields_from_env(env)
        try:
            return cls(**fields)
        except ValidationError as exc:
            first = exc.errors()[0]
            name = str(first["loc"][0]) if first["loc"] else ""
            var = sources.get(name) or ", ".join(sorted(set(sources.values()))) or name
            shown = "***" if name == "password" else first.get("input")
            message = str(first["msg"]).removeprefix("Value error, ")
            if not first["loc"]:       # a model-level rule (pairs of settings)
                raise ConfigError(f"{var}: {message}") from None
            if first["type"] == "value_error":   # our own checks already quote the value
                raise ConfigError(f"{var}: {message}") from None
            raise ConfigError(f"{var}: {message} (got {shown!r})") from None

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
        entries: list[tuple[str, object]] = []
        if "mode" in explicit:
            entries.append(("mode", self.mode))
        if "connect" in explicit:
            entries.append(("connect/endpoints", connect))
        if "listen" in explicit:
            entries.append(("listen/endpoints", listen))
        if "lease_ms" in explicit:
            entries.append(("transport/link/tx/lease", self.lease_ms))
        entries.append(("scouting/multicast/enabled", self.multicast))
        if self.config_file is None or "shared_memory" in self.model_fields_set:
            entries.append(("transport/shared_memory/enabled", self.shared_memory))
        if self.open_timeout_ms is not None:
            # The handshake bound only: connect/timeout_ms would also make a refused connection
            # retry until the timeout instead of failing at once.
            entries.append(("transport/unicast/open_timeout", self.open_timeout_ms))
        entries += self._security_entries()
        for key, value in entries:
            try:
                conf.insert_json5(key, json.dumps(value))
            except Exception as exc:  # noqa: BLE001
                raise ConfigError(f"invalid Zenoh setting {key} ({self.describe()}): {exc}"
                                  ) from None
        return conf

    def _security_entries(self) -> list[tuple[str, object]]:
        entries: list[tuple[str, object]] = []
        if self.user is not None and self.password is not None:
            entries += [("transport/auth/usrpwd/user", self.user),
                        ("transport/auth/usrpwd/password", self.password.get_secret_value())]
        if self.credentials_file is not None:
            check_credentials_file(self.credentials_file)
            entries.append(("transport/auth/usrpwd/dictionary_file",
                            str(self.credentials_file.resolve())))
        tls = "transport/link/tls"
        if self.tls_root_ca is not None:
            entries.append((f"{tls}/root_ca_certificate", str(self.tls_root_ca.resolve())))
        if self.tls_certificate is not None and self.tls_private_key is not None:
            cert, key = str(self.tls_certificate.resolve()), str(self.tls_private_key.resolve())
            # One identity for both roles: a router presents it to clients (listen_*), a client
            # presents it for mutual TLS (connect_*); a peer does both.
            entries += [(f"{tls}/listen_certificate", cert), (f"{tls}/listen_private_key", key),
                        (f"{tls}/connect_certificate", cert), (f"{tls}/connect_private_key", key)]
        if self.mtls:
            entries.append((f"{tls}/enable_mtls", True))
        if self.acl_file is not None:
            entries.append(("access_control", load_acl(self.acl_file)))
        return entries

    def describe(self) -> str:
        """One line for logs and errors (never the password)."""
        parts = [f"mode={self.mode}"]
        if self.connect and self.mode != "router":
            parts.append("connect=" + ",".join(self.connect))
        if self.listen:
            parts.append("listen=" + ",".join(self.listen))
        if self.config_file:
            parts.append(f"config={self.config_file}")
        if self.user:
            parts.append(f"user={self.user}")
        if self.credentials_file:
            parts.append(f"credentials={self.credentials_file}")
        if self.tls_root_ca or self.tls_certificate:
            parts.append("mtls" if self.mtls else "tls")
        if self.acl_file:
            parts.append(f"acl={self.acl_file}")
        return " ".join(parts)


def _fields_from_env(env: Mapping[str, str]) -> tuple[dict[str, object], dict[str, str]]:
    fields: dict[str, object] = {}
    sources: dict[str, str] = {}

    def value(var: str) -> str | None:
        text = env.get(var)
        return text.strip() if text is not None and text.strip() != "" else None

    if (mode := value(ENV_MODE)) is not None:
        fields["mode"], sources["mode"] = mode, ENV_MODE
    for name, var in (("connect", ENV_CONNECT), ("listen", ENV_LISTEN)):
        if (text := value(var)) is not None:
            fields[name] = [e.strip() for e in text.split(",") if e.strip()]
            sources[name] = var
    for name, var in _BOOL_VARS.items():
        if (text := value(var)) is not None:
            if text.lower() not in _TRUE + _FALSE:
                raise ConfigError(f"{var}={env[var]!r}: expected 0 or 1")
            fields[name], sources[name] = text.lower() in _TRUE, var
    if (text := value(ENV_LEASE)) is not None:
        fields["lease_ms"], sources["lease_ms"] = text, ENV_LEASE
    for name, var in _PATH_VARS.items():
        if (text := value(var)) is not None:
            fields[name], sources[name] = Path(text), var
    if (user := value(ENV_USER)) is not None:
        fields["user"], sources["user"] = user, ENV_USER
    password_file = value(ENV_PASSWORD_FILE)
    if value(ENV_PASSWORD) is not None and password_file is not None:
        raise ConfigError(f"set {ENV_PASSWORD} or {ENV_PASSWORD_FILE}, not both")
    if value(ENV_PASSWORD) is not None:
        fields["password"], sources["password"] = env[ENV_PASSWORD], ENV_PASSWORD
    elif password_file is not None:
        fields["password"] = _read_password(Path(password_file))
        sources["password"] = ENV_PASSWORD_FILE
    return fields, sources


def _read_password(path: Path) -> str:
    """First line of a file readable only by the service user (keeps it out of `ps e`)."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise ConfigError(f"{ENV_PASSWORD_FILE}={str(path)!r}: cannot read: {exc.strerror}"
                          ) from None
    if not lines or not lines[0]:
        raise ConfigError(f"{ENV_PASSWORD_FILE}={str(path)!r}: the first line must hold "
                          "the password")
    return lines[0]


def check_credentials_file(path: Path) -> None:
    """The usrpwd dictionary: one `user:password` per line; blank lines ignored.

    Why check it ourselves: Zenoh reports a malformed dictionary only as a failed open, or as
    every client being refused; an operator needs the line."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read credentials: {exc.strerror}") from None
    users: set[str] = set()
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        user, sep, password = line.partition(":")
        if not sep or not user or not password or user != user.strip():
            raise ConfigError(f"{path}:{number}: expected 'user:password'")
        if user in users:
            raise ConfigError(f"{path}:{number}: user {user!r} listed twice")
        users.add(user)
    if not users:
        raise ConfigError(f"{path}: no 'user:password' line")


def load_acl(path: Path) -> dict[str, Any]:
    """The `access_control` object of a json5 file `{access_control: {...}}`.

    Zenoh validates the schema (rule message kinds, flows, permissions); we add the cross
    references it does not report: a policy naming an unknown rule or subject makes the router
    silently deny everything, which looks like a network fault."""
    import zenoh
    try:
        document = json.loads(str(zenoh.Config.from_file(str(path))))
    except Exception as exc:  # noqa: BLE001 - ZError
        raise ConfigError(f"{path}: invalid access-control file: {exc}") from None
    acl = document.get("access_control") or {}
    if not acl.get("enabled"):
        raise ConfigError(f"{path}: access_control.enabled must be true (an ACL file that is "
                          "off protects nothing)")
    rules = {r.get("id") for r in acl.get("rules") or []}
    subjects = {s.get("id") for s in acl.get("subjects") or []}
    for index, policy in enumerate(acl.get("policies") or []):
        for kind, known in (("rules", rules), ("subjects", subjects)):
            for ident in policy.get(kind) or []:
                if ident not in known:
                    raise ConfigError(f"{path}: access_control.policies[{index}].{kind}: "
                                      f"unknown id {ident!r}")
    return acl


def graph_name_from_env(environ: Mapping[str, str] | None = None) -> str:
    env = os.environ if environ is None else environ
    name = env.get(ENV_GRAPH) or DEFAULT_GRAPH
    try:
        return check_agent_name(name, "graph")
    except ValueError as exc:
        raise ConfigError(f"{ENV_GRAPH}: {exc}") from None

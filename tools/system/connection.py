"""How a command reaches a running system: options -> endpoint, graph and credentials -> a replica.

Why shared: `chronav agenda` and `chronav dsr dump` take the same ``--run``/``--connect``/
``--graph`` options and must fail the same way, in a user's words: which option is malformed,
whether anything listens at the endpoint, whether it refused us for lack of the run's
credentials, which graphs and runs do exist.  First match wins: ``--connect``/``--graph``;
``--run DIR|ID|latest`` (the run's connect file, with its credentials, tools/system/runs.py); the
environment the agents use (``CHRONAV_ZENOH_*``, ``CHRONAV_GRAPH``); the user's newest live run;
the default router.
"""

from __future__ import annotations

import math
import os
import socket
from collections.abc import Iterator, Mapping, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tools.system.runs import HOW_TO_START, Identity, Role, RunError, list_runs, open_run, run_is_alive, runs_dir

# The help of the options every command that reaches a running system takes (one wording: they
# resolve alike, resolve_target below).
RUN_HELP = ("A run of `chronav launch`: 'latest' (your newest live run), a run directory, or a run id under "
            "./recordings ($CHRONAV_RUNS). Default: your newest live run, unless --connect, --graph or "
            "$CHRONAV_ZENOH_CONNECT/$CHRONAV_GRAPH name another system.")
GRAPH_HELP = "Graph name (default: the run's, $CHRONAV_GRAPH or 'chronav')."
CONNECT_HELP = "Zenoh endpoint(s) tcp/HOST:PORT (default: the run's, $CHRONAV_ZENOH_CONNECT or tcp/127.0.0.1:7447)."

HOW_TO_FIND = ("start one with `chronav launch SCENE` in this directory (with no --connect, --graph or "
               "CHRONAV_ZENOH_CONNECT/CHRONAV_GRAPH, commands find your newest live run under ./recordings or "
               "$CHRONAV_RUNS), or point this command at one with --run latest, --run <run directory>, or "
               "--connect tcp/HOST:PORT --graph <run id> (with the run's credentials)")


class ConnectionProblem(Exception):
    """The command cannot reach a usable system; the message says what to do."""


@dataclass(frozen=True)
class Target:
    """Router endpoints, graph name and identity, plus where they came from (for messages)."""

    connect: tuple[str, ...]
    graph: str
    origin: str
    run_dir: Path | None = None
    identity: Identity | None = None

    def describe(self) -> str:
        return f"graph {self.graph!r} via {','.join(self.connect)} ({self.origin})"


def check_timeout(value: float, option: str = "--timeout") -> float:
    """A wait in seconds: finite and > 0, else a message naming the option."""
    if not math.isfinite(value) or value <= 0:
        raise ConnectionProblem(f"{option} {value:g}: give a number of seconds greater than 0")
    return value


def resolve_target(connect: Sequence[str] | None, graph: str | None, run: str | None, *, role: Role,
                   environ: Mapping[str, str] | None = None, runs: Path | None = None) -> Target:
    """Explicit options beat --run, which beats the environment the agents use; with none of
    them, the user's newest live run under the runs directory (what `chronav launch` just
    started), else the default router (a system started by hand, `python -m dsr.router`)."""
    from dsr.config import DEFAULT_ROUTER, ENV_CONNECT, ENV_GRAPH, check_endpoint, graph_name_from_env
    from dsr.errors import ConfigError
    from dsr.model import check_agent_name

    env = os.environ if environ is None else environ
    endpoints: list[str] = []
    for text in connect or ():
        try:
            endpoints.append(check_endpoint(text))
        except ConfigError as exc:
            raise ConnectionProblem(f"--connect {exc}") from None
    if graph is not None and graph != "":
        try:
            check_agent_name(graph, "graph")
        except ValueError as exc:
            raise ConnectionProblem(f"--graph {graph!r}: {exc}") from None
    looked = newest = ""
    directory = runs or runs_dir(env)
    env_endpoints = [e for e in env.get(ENV_CONNECT, "").split(",") if e.strip()]
    names_a_system = endpoints or graph or env.get(ENV_GRAPH) or env_endpoints
    if not run and not names_a_system:       # what `chronav launch` here just started, if any
        live = list_runs(directory).mine_live
        if live:       # then opened as --run <its directory> is
            run, newest = str(live[0]), ", your newest live run"
        else:
            looked = f"no live run of yours under {directory}; "
    if run:
        try:
            info = open_run(run, directory)
        except RunError as exc:
            raise ConnectionProblem(str(exc)) from None
        base = Target((info.endpoint,), info.graph, f"run {info.run_id}{newest}", info.run_dir, info.identity(role))
    else:
        try:
            env_graph = graph_name_from_env(env)
            env_connect = [check_endpoint(e) for e in env_endpoints]
        except ConfigError as exc:
            raise ConnectionProblem(f"{ENV_CONNECT}: {exc}" if ENV_CONNECT not in str(exc) else str(exc)) from None
        origin = looked + (f"from {ENV_CONNECT}" if env_connect else f"default; {ENV_CONNECT} is not set") + (
            f", {ENV_GRAPH}" if env.get(ENV_GRAPH) else f", default graph; {ENV_GRAPH} is not set")
        base = Target(tuple(env_connect or [DEFAULT_ROUTER]), env_graph, origin)
    if endpoints or graph:
        base = Target(tuple(endpoints) if endpoints else base.connect, graph or base.graph,
                      "from --connect/--graph" if endpoints and graph else
                      f"{'--connect' if endpoints else '--graph'} over {base.origin}", base.run_dir, base.identity)
    return base


def settings_for(target: Target, *, open_timeout_s: float | None = None,
                 environ: Mapping[str, str] | None = None) -> Any:
    """Client settings for ``target``: the environment's (TLS, lease...) with the target's
    endpoints, the run's identity when it has one, and a bound on opening the session."""
    from pydantic import ValidationError

    from dsr import DSRError, ZenohSettings

    try:
        base = ZenohSettings.from_env(environ)
        fields = base.model_dump(exclude_unset=True)
        if base.password is not None:
            fields["password"] = base.password
        fields.update(mode="client", connect=list(target.connect))
        if target.identity is not None:
            fields.update(user=target.identity.user, password=target.identity.password)
        if open_timeout_s is not None:
            fields["open_timeout_ms"] = max(1, min(3_600_000, round(open_timeout_s * 1000)))
        return ZenohSettings(**fields)
    except (DSRError, ValidationError) as exc:
        raise ConnectionProblem(f"bad connection settings ({target.describe()}): {exc}") from None


def _listening(endpoint: str, timeout_s: float = 1.0) -> bool | None:
    """Does anything accept TCP connections at a tcp/tls endpoint?  None for other protocols."""
    protocol, _, address = endpoint.partition("/")
    if protocol not in ("tcp", "tls", "ws"):
        return None
    host, _, port = address.split("#")[0].split("?")[0].rpartition(":")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s):
            return True
    except (OSError, ValueError):
        return False


def unreachable_message(target: Target) -> str:
    """Why a session could not be opened, probed on the network, and what to do."""
    parts = []
    for endpoint in target.connect:
        listening = _listening(endpoint)
        if listening is False:
            parts.append(f"nothing listens at {endpoint}")
        elif listening:
            refused = f"something listens at {endpoint} but refused a chronav session: it is not a Zenoh router"
            if target.identity is None:
                parts.append(refused + ", or it requires credentials (runs of `chronav launch` do: join them "
                             "with --run latest or --run <run directory>, which reads the run's connect.json)")
            else:
                parts.append(refused + f", or it no longer accepts the credentials of {target.origin}")
        else:
            parts.append(f"no Zenoh session could be opened at {endpoint}")
    text = f"cannot reach a chronav system: {'; '.join(parts)} ({target.origin})"
    if target.run_dir is not None and not run_is_alive(target.run_dir):
        return f"{text}; run {target.run_dir.name} is no longer running; {HOW_TO_START}"
    return f"{text}; {HOW_TO_FIND}"


@contextmanager
def open_replica(target: Target, *, agent: str, read_only: bool, timeout_s: float) -> Iterator[Any]:
    """A replica of the target's graph for the block, opened and synchronised within
    ``timeout_s`` each; connection problems become ConnectionProblem."""
    from dsr import DSRError, join
    from dsr.transport import TransportError

    settings = settings_for(target, open_timeout_s=timeout_s)
    stack = ExitStack()
    try:
        graph = stack.enter_context(join(agent, graph=target.graph, settings=settings, read_only=read_only,
                                         sync_timeout=timeout_s))
    except TransportError:
        raise ConnectionProblem(unreachable_message(target)) from None
    except DSRError as exc:
        raise ConnectionProblem(f"cannot join {target.describe()}: {exc}") from None
    with stack:
        yield graph


def members(graph: Any, timeout_s: float = 2.0) -> list[str] | None:
    """Agents with a writable replica in the graph (liveliness tokens); None when offline."""
    from dsr import wire

    session = getattr(getattr(graph, "replica", None), "session", None)
    if session is None:
        return None
    replies = session.liveliness().get(wire.member_key(graph.graph_name, "*"), timeout=timeout_s)
    return sorted({wire.last_chunk(str(r.ok.key_expr)) for r in replies if r.ok is not None})


def graphs_with_members(graph: Any, timeout_s: float = 2.0) -> list[str]:
    """Names of the graphs that have members on the same router (those this identity may see)."""
    from dsr import wire

    session = getattr(getattr(graph, "replica", None), "session", None)
    if session is None:
        return []
    names = set()
    for reply in session.liveliness().get(wire.member_key("*", "*"), timeout=timeout_s):
        if reply.ok is not None:
            chunks = str(reply.ok.key_expr).split("/")
            if len(chunks) >= 4:
                names.add(chunks[1])
    return sorted(names)


def require_system(graph: Any, target: Target) -> list[str]:
    """The graph's other members; ConnectionProblem when nobody uses that graph name, naming the
    graphs and the runs that do exist (an empty dump of a misspelt graph helps nobody)."""
    present = members(graph)
    others = [m for m in present or [] if m != graph.agent]
    if present is None or others or len(graph) > 0:
        return others
    if target.run_dir is not None and run_is_alive(target.run_dir):
        raise ConnectionProblem(f"run {target.run_dir.name} is live but no agent has joined its graph yet (it is "
                                f"starting, or its agents are down: see {target.run_dir / 'logs'}); retry in a moment")
    hints = []
    graphs = [g for g in graphs_with_members(graph) if g != target.graph]
    if graphs:
        hints.append(f"graphs with members there: {', '.join(graphs)} (use --graph NAME)")
    try:
        live = list_runs(runs_dir()).mine_live
    except OSError:
        live = []
    if live:
        hints.append(f"your live runs under {runs_dir()}: {', '.join(p.name for p in live[:5])} "
                     "(use --run latest or --run NAME)")
    hint = "; ".join(hints) if hints else HOW_TO_FIND
    raise ConnectionProblem(f"joined {target.describe()} but nobody is there: no chronav system uses the "
                            f"graph name {target.graph!r} (it is the run id, see the run's connect.json); {hint}")


def stats_reports(session: Any, key: str, wanted_format: str, timeout_s: float) -> Iterator[dict[str, Any]]:
    """The JSON reports that answer ``KEY?stats`` (every queryable asked, no reply merged) and
    carry ``"format": wanted_format``.

    Why a filter and not an error: anything may answer on a key (a member of another version, a
    foreign queryable); a reply that is an error, not JSON or of another format is skipped."""
    import orjson
    import zenoh

    for reply in session.get(key + "?stats", target=zenoh.QueryTarget.ALL,
                             consolidation=zenoh.ConsolidationMode.NONE, timeout=timeout_s):
        if reply.ok is None:
            continue
        try:
            report = orjson.loads(reply.ok.payload.to_bytes())
        except orjson.JSONDecodeError:
            continue
        if isinstance(report, dict) and report.get("format") == wanted_format:
            yield report


def graph_stats(session: Any, graph_name: str, timeout_s: float) -> dict[str, Any]:
    """Every member's counters (members answer ``chronav/<g>/state/<agent>?stats``) and the
    router's ACL denials (dsr/acl_denials.py; None from a router without an ACL, or one that is
    not chronav's dsr.router): ``{"members": {agent: report}, "router": report or None}``.

    Why here: `chronav dsr stats` prints this and `chronav chaos` sums its trust counters; one
    query, so both read the same numbers."""
    from dsr import wire
    from dsr.acl_denials import FORMAT as ROUTER_FORMAT, stats_key
    from dsr.transport import STATS_FORMAT

    router = next(stats_reports(session, stats_key(graph_name), ROUTER_FORMAT, timeout_s), None)
    members = {str(report.get("agent")): report
               for report in stats_reports(session, wire.state_key(graph_name, "*"), STATS_FORMAT, timeout_s)}
    return {"members": dict(sorted(members.items())), "router": router}

"""`chronav dsr dump` / `chronav dsr stats`: inspect a running graph from outside.

`dump` joins a running graph read-only and prints it, or follows its changes.  `stats` asks
every member for its replica counters (received, applied, refusals per reason, tombstones...):
the dump's own short-lived replica has received nothing worth counting.

Read-only replicas declare no publisher, queryable or liveliness token: the dump is invisible
to the agents and can never write.  Output: a rich table, or with --json one JSON object (the
graph document of dsr/files.py plus "graph" and "stats").  With --follow the changes are printed
as they arrive (with --json: one JSON object per line, the first being the full graph).
"""

from __future__ import annotations

import os
import sys
import time
from typing import Any

import typer

dsr_app = typer.Typer(help="Inspect the replicated DSR graph.", no_args_is_help=True)


def register(app: typer.Typer) -> None:
    app.add_typer(dsr_app, name="dsr")


def _event_json(signal: str, args: tuple[Any, ...]) -> dict[str, Any]:
    if signal.startswith("node_"):
        if signal == "node_deleted":
            return {"signal": signal, "id": args[0]}
        node = args[0]
        out = {"signal": signal, "node": {"id": node.id, "type": node.type, "name": node.name,
                                          "attrs": node.attrs}}
        if signal == "node_updated":
            out["changed"] = args[1]
        return out
    if signal == "edge_deleted":
        return {"signal": signal, "src": args[0], "dst": args[1], "type": args[2]}
    edge = args[0]
    out = {"signal": signal, "edge": {"src": edge.src, "dst": edge.dst, "type": edge.type,
                                      "attrs": edge.attrs}}
    if signal == "edge_updated":
        out["changed"] = args[1]
    return out


def _event_text(graph: Any, signal: str, args: tuple[Any, ...]) -> str:
    def name(node_id: int) -> str:
        node = graph.get_node(node_id)
        return node.name if node is not None else str(node_id)
    if signal == "node_deleted":
        return f"- node {args[0]}"
    if signal.startswith("node_"):
        node = args[0]
        mark = "+" if signal == "node_added" else "~"
        shown = node.attrs if signal == "node_added" else {k: node.attrs.get(k) for k in args[1]}
        return f"{mark} node {node.name} ({node.type}, {node.id}) {shown}"
    if signal == "edge_deleted":
        return f"- edge {name(args[0])} -{args[2]}-> {name(args[1])}"
    edge = args[0]
    mark = "+" if signal == "edge_added" else "~"
    return f"{mark} edge {name(edge.src)} -{edge.type}-> {name(edge.dst)} {edge.attrs}"


def _print_tables(graph: Any) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console()
    nodes = Table(title=f"DSR graph {graph.graph_name!r}: {len(graph)} nodes")
    for column in ("id", "type", "name", "attrs"):
        nodes.add_column(column, overflow="fold")
    for node in graph.nodes():
        nodes.add_row(str(node.id), node.type, node.name, _short(node.attrs))
    console.print(nodes)
    edge_list = graph.edges()
    edges = Table(title=f"{len(edge_list)} edges")
    for column in ("from", "type", "to", "attrs"):
        edges.add_column(column, overflow="fold")
    for edge in edge_list:
        src, dst = graph.get_node(edge.src), graph.get_node(edge.dst)
        edges.add_row(src.name if src else str(edge.src), edge.type,
                      dst.name if dst else str(edge.dst), _short(edge.attrs))
    console.print(edges)


def _short(attrs: dict[str, Any]) -> str:
    parts = []
    for key, value in sorted(attrs.items()):
        if isinstance(value, float):
            parts.append(f"{key}={value:.3g}")
        else:
            parts.append(f"{key}={value!r}")
    return ", ".join(parts)


@dsr_app.command("dump")
def dump(
    json_output: bool = typer.Option(False, "--json", help="Print JSON instead of tables."),
    follow: bool = typer.Option(False, "--follow", "-f", help="Keep printing changes live."),
    graph_name: str = typer.Option("", "--graph", help="Graph name (default $CHRONAV_GRAPH or "
                                   "'chronav')."),
    connect: list[str] = typer.Option([], "--connect", help="Zenoh endpoint(s) to connect to "
                                      "(default $CHRONAV_ZENOH_CONNECT or tcp/127.0.0.1:7447)."),
    duration: float = typer.Option(0.0, "--duration", help="With --follow: stop after this many "
                                   "seconds (0 = until Ctrl-C)."),
    timeout: float = typer.Option(5.0, "--timeout", help="Seconds to wait for the state."),
) -> None:
    """Join a running graph read-only and print it (table or JSON), or follow changes live."""
    import orjson

    from dsr import SIGNALS, DSRError, ZenohSettings, graph_name_from_env, join
    from dsr.process import exit_on_sigterm

    try:
        settings = ZenohSettings.from_env()
        if connect:
            settings = ZenohSettings(**{**settings.model_dump(exclude_unset=True),
                                        "connect": connect})
        name = graph_name or graph_name_from_env()
    except (DSRError, ValueError) as exc:
        typer.echo(f"chronav dsr dump: {exc}", err=True)
        raise typer.Exit(2) from None
    exit_on_sigterm()
    try:
        with join(f"dump-{os.getpid()}", graph=name, settings=settings,
                  read_only=True, sync_timeout=timeout) as graph:
            document = {"graph": name, **graph.to_document(),
                        "stats": graph.replica.stats.as_dict()}
            if json_output:
                sys.stdout.write(orjson.dumps(document).decode() + "\n")
            else:
                _print_tables(graph)
            sys.stdout.flush()
            if not follow:
                return
            for signal in SIGNALS:
                def emit(*args: Any, _signal: str = signal) -> None:
                    if json_output:
                        line = orjson.dumps(_event_json(_signal, args)).decode()
                    else:
                        line = _event_text(graph, _signal, args)
                    sys.stdout.write(line + "\n")
                    sys.stdout.flush()
                graph.connect(signal, emit)
            deadline = time.monotonic() + duration if duration > 0 else None
            while deadline is None or time.monotonic() < deadline:
                graph.dispatch(timeout=0.2)
    except DSRError as exc:
        typer.echo(f"chronav dsr dump: {exc}", err=True)
        raise typer.Exit(1) from None
    except KeyboardInterrupt:
        raise typer.Exit(130) from None


def _settings(connect: list[str]) -> Any:
    from dsr import ZenohSettings
    settings = ZenohSettings.from_env()
    if connect:
        settings = ZenohSettings(**{**settings.model_dump(exclude_unset=True), "connect": connect})
    return settings


def collect_stats(settings: Any, graph_name: str, timeout: float) -> dict[str, Any]:
    """Every member's counters, by agent (members answer `chronav/<g>/state/<agent>?stats`)."""
    import orjson
    import zenoh

    from dsr import wire
    from dsr.transport import STATS_FORMAT, TransportError

    try:
        session = zenoh.open(settings.to_zenoh_config())
    except zenoh.ZError as exc:
        raise TransportError(f"cannot open Zenoh session ({settings.describe()}): {exc}; is "
                             "the system running (chronav launch)?") from None
    members: dict[str, Any] = {}
    try:
        replies = session.get(wire.state_key(graph_name, "*") + "?stats",
                              target=zenoh.QueryTarget.ALL,
                              consolidation=zenoh.ConsolidationMode.NONE, timeout=timeout)
        for reply in replies:
            if reply.ok is None:
                continue
            try:
                report = orjson.loads(reply.ok.payload.to_bytes())
            except orjson.JSONDecodeError:
                continue
            if isinstance(report, dict) and report.get("format") == STATS_FORMAT:
                members[str(report.get("agent"))] = report
    finally:
        session.close()
    return {"graph": graph_name, "members": dict(sorted(members.items()))}


@dsr_app.command("stats")
def stats(
    json_output: bool = typer.Option(False, "--json", help="Print JSON instead of a table."),
    graph_name: str = typer.Option("", "--graph", help="Graph name (default $CHRONAV_GRAPH or "
                                   "'chronav')."),
    connect: list[str] = typer.Option([], "--connect", help="Zenoh endpoint(s) to connect to "
                                      "(default $CHRONAV_ZENOH_CONNECT or tcp/127.0.0.1:7447)."),
    timeout: float = typer.Option(5.0, "--timeout", help="Seconds to wait for the answers."),
) -> None:
    """Every member's replica counters: deltas received and applied, refusals per reason,
    deferred relayed writes, digests, tombstones held and compacted."""
    import orjson

    from dsr import DSRError, graph_name_from_env

    try:
        settings = _settings(connect)
        name = graph_name or graph_name_from_env()
        document = collect_stats(settings, name, timeout)
    except (DSRError, ValueError) as exc:
        typer.echo(f"chronav dsr stats: {exc}", err=True)
        raise typer.Exit(1) from None
    if not document["members"]:
        typer.echo(f"chronav dsr stats: no member of graph {name!r} answered within {timeout} s "
                   "(is the system running, and is --graph right?)", err=True)
        raise typer.Exit(1)
    if json_output:
        sys.stdout.write(orjson.dumps(document).decode() + "\n")
        return
    from rich.console import Console
    from rich.table import Table
    table = Table(title=f"DSR graph {name!r}: {len(document['members'])} members")
    for column in ("agent", "nodes", "received", "applied", "published", "refused (by reason)",
                   "policy", "deferred", "tombstones", "compacted"):
        table.add_column(column, overflow="fold")
    for agent, report in document["members"].items():
        counters = report.get("stats", {})
        reasons = ", ".join(f"{k}={v}" for k, v in sorted((counters.get("rejects") or {}).items()))
        table.add_row(agent, str(report.get("nodes")), str(counters.get("received")),
                      str(counters.get("applied")), str(counters.get("published")),
                      reasons or "0", str(counters.get("rejected_policy")),
                      str(counters.get("deferred")), str(report.get("tombstones")),
                      str(counters.get("compacted")))
    Console().print(table)

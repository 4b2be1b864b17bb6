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
from typing import TYPE_CHECKING, Any

import typer

from tools.system.connection import CONNECT_HELP, GRAPH_HELP, RUN_HELP, Target

if TYPE_CHECKING:
    from dsr import DSRGraph

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
        keys = sorted(node.attrs) if signal == "node_added" else list(args[1])
        shown = ", ".join(attr_text(k, node.attrs.get(k)) for k in keys)
        return f"{mark} node {node.name} ({node.type}, {node.id}) {shown}"
    if signal == "edge_deleted":
        return f"- edge {name(args[0])} -{args[2]}-> {name(args[1])}"
    edge = args[0]
    mark = "+" if signal == "edge_added" else "~"
    shown = ", ".join(attr_text(k, v) for k, v in sorted(edge.attrs.items()))
    return f"{mark} edge {name(edge.src)} -{edge.type}-> {name(edge.dst)} {shown}"


# The attributes the compact dump shows for each node type (``--all`` shows every one); other types
# show their scalar attributes.  What a person checks first: where things are, their state, times.
KEY_ATTRS: dict[str, tuple[str, ...]] = {
    "clock": ("now_s", "mode", "rate", "start_s", "end_s", "finished"),
    "robot": ("v", "omega", "nav_active", "path_cost", "planned_s", "pose_stamp"),
    "person": ("role", "seen_s", "vx", "vy"),
    "object": ("kind", "R", "R_band", "active"),
    "door": ("open", "width", "rooms"),
    "activity": ("state", "start_s", "end_s", "object", "room"),
    "mission": ("goal", "time_s", "state", "started_s", "finished_s", "reason"),
    "intention": ("mission_id", "kind", "state", "target", "issued_s", "until_s", "reason"),
    "agenda_request": ("state", "requested_by", "requested_s", "message"),
    "agenda": ("applied",),
    "heartbeat": ("beat", "pid"),
    "sensor": ("observed_s",),
    "ground_truth": ("stamp",),
    "room": (),
}


def is_clock_key(key: str) -> bool:
    """Attributes holding a time of the sim day (seconds since midnight): shown as HH:MM:SS.
    ``wall_s`` is a wall-clock epoch, not a time of day."""
    return (key.endswith("_s") and key != "wall_s") or key.endswith("stamp")


def attr_text(key: str, value: Any, *, all_items: bool = False) -> str:
    """``key=value`` for a person: times of day as HH:MM:SS, floats with 2 decimals (never
    ``3.24e+04``); unless ``all_items``, long lists are summarised and text is unquoted and cut."""
    from scenes.clock import format_clock

    if isinstance(value, bool) or value is None:
        shown = str(value)
    elif isinstance(value, (int, float)) and is_clock_key(key):
        shown = format_clock(float(value))
    elif isinstance(value, float):
        shown = f"{value:.2f}"
    elif isinstance(value, (list, tuple)):
        items = [f"{v:.2f}" if isinstance(v, float) else str(v) for v in value]
        shown = "[" + ", ".join(items if all_items or len(items) <= 4 else [*items[:3], f"... {len(items):,} items"]) + "]"
    elif isinstance(value, str) and not all_items:
        shown = value if len(value) <= 60 else value[:57] + "..."
    else:
        shown = repr(value) if isinstance(value, str) else str(value)
    return f"{key}={shown}"


def _node_pose(graph: Any, node_id: int) -> str:
    """``@(x, y)`` from the RT edge that places the node in its parent, if any."""
    from agents.world.vocabulary import EdgeType

    for edge in graph.edges_to(node_id, EdgeType.RT):
        if "x" in edge.attrs and "y" in edge.attrs:
            return f"@({float(edge.attrs['x']):.2f}, {float(edge.attrs['y']):.2f}) "
    return ""


def dump_lines(graph: Any, width: int, *, all_attrs: bool) -> list[str]:
    """The graph grouped by node type, then edges by type.  Compact: one line per node (its key
    attributes, cut at ``width``); ``all_attrs``: every attribute, wrapped between attributes."""
    from agents.world.vocabulary import EdgeType, NodeType
    from tools.plain import cut, plural, wrapped

    nodes = sorted(graph.nodes(), key=lambda n: (n.type, n.name))
    edges = graph.edges()
    lines = [f"DSR graph {graph.graph_name!r}: {plural(len(nodes), 'node')}, {plural(len(edges), 'edge')}"
             + ("" if all_attrs else " (key attributes; --all for every one)")]
    by_type: dict[str, list[Any]] = {}
    for node in nodes:
        by_type.setdefault(node.type, []).append(node)
    for node_type, group in by_type.items():
        lines.append(f"{node_type} ({len(group)})")
        for node in group:
            keys = sorted(node.attrs) if all_attrs else [
                k for k in KEY_ATTRS.get(node_type, sorted(node.attrs)) if k in node.attrs
                and (node_type in KEY_ATTRS or not isinstance(node.attrs[k], (list, dict)))]
            attrs = ", ".join(attr_text(k, node.attrs[k], all_items=all_attrs) for k in keys)
            where = "" if node_type == NodeType.ROOM else _node_pose(graph, node.id)   # a room's frame is not a place
            head = f"  {node.name} [{node.id}] {where}" if all_attrs else f"  {node.name} {where}"
            if all_attrs:
                lines += wrapped(head + attrs, width, indent="      ")
            else:
                lines.append(cut((head + attrs).rstrip(), width))
    names = {n.id: n.name for n in nodes}
    by_edge: dict[str, list[Any]] = {}
    for edge in edges:
        by_edge.setdefault(edge.type, []).append(edge)
    for edge_type, group in sorted(by_edge.items()):
        group = sorted(group, key=lambda e: (names.get(e.src, ""), names.get(e.dst, "")))
        if all_attrs:
            lines.append(f"edges {edge_type} ({len(group)})")
            for edge in group:
                attrs = ", ".join(attr_text(k, v, all_items=True) for k, v in sorted(edge.attrs.items()))
                lines += wrapped(f"  {names.get(edge.src, edge.src)} -> {names.get(edge.dst, edge.dst)} {attrs}",
                                 width, first="  ", indent="      ")
        elif edge_type == EdgeType.RT:     # the poses are on the nodes, as @(x, y)
            lines.append(f"edges RT ({len(group)}): the poses shown as @(x, y) above")
        else:                       # one line per source: its targets, wrapped between names
            lines.append(f"edges {edge_type} ({len(group)})")
            targets: dict[Any, list[str]] = {}
            for edge in group:
                targets.setdefault(edge.src, []).append(str(names.get(edge.dst, edge.dst)))
            for src, dsts in targets.items():
                lines += wrapped(f"{names.get(src, src)} -> {', '.join(dsts)}", width, first="  ", indent="      ")
    return lines


def _print_tables(graph: Any, all_attrs: bool = False) -> None:
    from rich.console import Console

    from tools.plain import console_width, print_lines

    console = Console()
    print_lines(console, dump_lines(graph, console_width(console), all_attrs=all_attrs))


@dsr_app.command("dump")
def dump(
    json_output: bool = typer.Option(False, "--json", help="Print JSON instead of tables."),
    follow: bool = typer.Option(False, "--follow", "-f", help="Keep printing changes live."),
    run: str = typer.Option(None, "--run", help=RUN_HELP),
    graph_name: str = typer.Option(None, "--graph", help=GRAPH_HELP),
    connect: list[str] = typer.Option([], "--connect", help=CONNECT_HELP),
    duration: float = typer.Option(0.0, "--duration", help="With --follow: stop after this many "
                                   "seconds (0 = until Ctrl-C)."),
    timeout: float = typer.Option(5.0, "--timeout", help="Seconds to wait for the connection, and "
                                  "again for the state."),
    all_attrs: bool = typer.Option(False, "--all", help="Every attribute of every node and edge (default: "
                                   "one line per node with its key attributes)."),
    output_format: str = typer.Option("table", "--format",
                                      help="table, json, or agm-xml (RoboComp AGM world XML, for AGM "
                                           "tools; not with --follow)."),
) -> None:
    """Join a running graph read-only and print it (table or JSON), or follow changes live."""
    json_output = _dump_json_output(output_format, follow, json_output)

    from dsr.process import exit_on_sigterm
    from tools.system.connection import ConnectionProblem, open_replica, require_system

    target = _dump_target(connect, graph_name, run, timeout)
    exit_on_sigterm()
    try:
        with open_replica(target, agent=f"dump-{os.getpid()}", read_only=True,
                          timeout_s=timeout) as graph:
            require_system(graph, target)
            _print_snapshot(graph, target.graph, output_format, json_output, all_attrs)
            if not follow:
                return
            _follow(graph, json_output, duration)
    except ConnectionProblem as exc:
        typer.echo(f"chronav dsr dump: {exc}", err=True)
        raise typer.Exit(1) from None
    except KeyboardInterrupt:
        raise typer.Exit(130) from None


def _dump_json_output(output_format: str, follow: bool, json_output: bool) -> bool:
    """Whether the dump prints JSON (``--json`` or ``--format json``); exit 2 on a format it cannot do."""
    if output_format not in ("table", "json", "agm-xml"):
        typer.echo(f"chronav dsr dump: --format {output_format!r}: use table, json or agm-xml", err=True)
        raise typer.Exit(2)
    if output_format == "agm-xml" and (follow or json_output):
        typer.echo("chronav dsr dump: --format agm-xml writes one snapshot: drop --follow and --json", err=True)
        raise typer.Exit(2)
    return json_output or output_format == "json"


def _dump_target(connect: list[str], graph_name: str | None, run: str | None, timeout: float) -> Target:
    """The graph to read, from --connect/--graph/--run (exit 2 with the reason if none fits)."""
    from tools.system.connection import ConnectionProblem, check_timeout, resolve_target

    try:
        check_timeout(timeout)
        return resolve_target(connect, graph_name, run, role="reader")
    except ConnectionProblem as exc:
        typer.echo(f"chronav dsr dump: {exc}", err=True)
        raise typer.Exit(2) from None


def _print_snapshot(graph: DSRGraph, name: str, output_format: str, json_output: bool,
                    all_attrs: bool = False) -> None:
    """The whole graph once: AGM world XML, one JSON document, or the text grouped by type."""
    import orjson

    document = {"graph": name, **graph.to_document(),
                "stats": graph.replica.stats.as_dict()}
    if output_format == "agm-xml":
        from grammar.agm_world import agm_world_xml

        sys.stdout.write(agm_world_xml(graph.to_networkx()))
    elif json_output:
        sys.stdout.write(orjson.dumps(document).decode() + "\n")
    else:
        _print_tables(graph, all_attrs)
    sys.stdout.flush()


def _follow(graph: DSRGraph, json_output: bool, duration: float) -> None:
    """Print every change as it arrives (a JSON object or a line of text each), for ``duration``
    seconds or, with 0, until interrupted."""
    import orjson

    from dsr import SIGNALS

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


def collect_stats(target: Any, timeout: float) -> dict[str, Any]:
    """Every member's counters, by agent, and the router's ACL denials (tools/system/connection.py)."""
    import zenoh

    from tools.system.connection import ConnectionProblem, graph_stats, settings_for, unreachable_message

    settings = settings_for(target, open_timeout_s=timeout)
    try:
        session = zenoh.open(settings.to_zenoh_config())
    except zenoh.ZError:
        raise ConnectionProblem(unreachable_message(target)) from None
    try:
        stats = graph_stats(session, target.graph, timeout)
    finally:
        session.close()
    return {"graph": target.graph, **stats}


@dsr_app.command("stats")
def stats(
    json_output: bool = typer.Option(False, "--json", help="Print JSON instead of a table."),
    run: str = typer.Option(None, "--run", help=RUN_HELP),
    graph_name: str = typer.Option(None, "--graph", help=GRAPH_HELP),
    connect: list[str] = typer.Option([], "--connect", help=CONNECT_HELP),
    timeout: float = typer.Option(5.0, "--timeout", help="Seconds to wait for the connection, and "
                                  "again for the answers."),
) -> None:
    """Every member's replica counters: deltas received and applied, refusals per reason,
    deferred relayed writes, digests, tombstones held and compacted."""
    import orjson

    from tools.system.connection import ConnectionProblem, check_timeout, resolve_target

    try:
        check_timeout(timeout)
        target = resolve_target(connect, graph_name, run, role="reader")
    except ConnectionProblem as exc:
        typer.echo(f"chronav dsr stats: {exc}", err=True)
        raise typer.Exit(2) from None
    try:
        document = collect_stats(target, timeout)
    except ConnectionProblem as exc:
        typer.echo(f"chronav dsr stats: {exc}", err=True)
        raise typer.Exit(1) from None
    if not document["members"]:
        typer.echo(f"chronav dsr stats: no member of graph {target.graph!r} answered within "
                   f"{timeout:g} s ({target.describe()}): is the system running, and is --graph "
                   "right?", err=True)
        raise typer.Exit(1)
    if json_output:
        sys.stdout.write(orjson.dumps(document).decode() + "\n")
        return
    _print_stats(target.graph, document)


def stats_lines(graph_name: str, document: dict[str, Any], width: int) -> list[str]:
    """The members' counters as a plain layout (pipes, logs): one entry per member, wrapped between
    words, where the eleven-column table would be cut at 80 columns."""
    from tools.plain import plural, wrapped

    lines = [f"DSR graph {graph_name!r}: {plural(len(document['members']), 'member')}"]
    for agent, report in document["members"].items():
        c = report.get("stats", {})
        reasons = ", ".join(f"{k}={v}" for k, v in sorted((c.get("rejects") or {}).items())) or "0"
        lines += wrapped(f"{agent}: nodes {report.get('nodes')}, received {c.get('received')}, applied "
                         f"{c.get('applied')}, published {c.get('published')}, refused {reasons}, policy "
                         f"{c.get('rejected_policy')}, deferred {c.get('deferred')}, fetches {c.get('syncs')} "
                         f"(held back {c.get('fetches_postponed', 0)}), tombstones {report.get('tombstones')}, "
                         f"compacted {c.get('compacted')}", width, first="  ", indent="      ")
    return lines


def _print_stats(graph_name: str, document: dict[str, Any]) -> None:
    """The members' counters as a table (a plain layout when not on a terminal), then what the
    router's ACL denied."""
    from rich.console import Console
    from rich.table import Table

    from tools.plain import console_width, is_plain, print_lines

    console = Console()
    if is_plain(console):
        print_lines(console, stats_lines(graph_name, document, console_width(console)))
        _print_router(document)
        return
    table = Table(title=f"DSR graph {graph_name!r}: {len(document['members'])} members")
    for column in ("agent", "nodes", "received", "applied", "published", "refused (by reason)",
                   "policy", "deferred", "fetches (held back)", "tombstones", "compacted"):
        table.add_column(column, overflow="fold")
    for agent, report in document["members"].items():
        counters = report.get("stats", {})
        reasons = ", ".join(f"{k}={v}" for k, v in sorted((counters.get("rejects") or {}).items()))
        table.add_row(agent, str(report.get("nodes")), str(counters.get("received")),
                      str(counters.get("applied")), str(counters.get("published")),
                      reasons or "0", str(counters.get("rejected_policy")),
                      str(counters.get("deferred")),
                      f"{counters.get('syncs')} ({counters.get('fetches_postponed', 0)})",
                      str(report.get("tombstones")),
                      str(counters.get("compacted")))
    console.print(table)
    _print_router(document)


def _print_router(document: dict[str, Any]) -> None:
    router = document.get("router")
    if router is not None and not router.get("acl", True):
        typer.echo("router: no access-control list (nothing is denied or counted)")
    elif router is not None:
        kinds = "; ".join(f"{d['message']} on {d['key']} by {d['user']!r}: {d['count']}"
                          for d in router.get("denials", [])[:10])
        typer.echo(f"router: {router.get('acl_denied', 0)} message(s) denied by the ACL"
                   + (f" ({kinds})" if kinds else ""))

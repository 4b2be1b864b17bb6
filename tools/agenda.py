"""`chronav agenda`: read and change the agenda of a running chronav system from a terminal.

Why the tool is just another DSR replica (and not an RPC to the agenda agent): the request, who
made it and the agent's answer are then replicated and recorded like everything else, and the
tool needs nothing but the router's address and the graph name.  Protocol (agents/agenda/agent.py):
insert ``agenda_request/<uuid>`` with ``change`` (JSON, agents/agenda/changes.py) and
``state="pending"``; the agenda agent applies the whole change or nothing and sets ``state`` to
``accepted``/``refused`` with a ``message``; the tool prints it and deletes the request node.

Finding the system, first match wins (tools/system/connection.py): ``--connect``/``--graph``;
``--run DIR|ID|latest`` (the ``connect.json`` that `chronav launch` writes in its run directory,
with the run's credentials: changes are sent as the run's tool identity, which may write only as
an ``agenda_tool-*`` agent; ``list`` and ``watch`` join as its read-only reader); the environment
(``CHRONAV_ZENOH_*``, ``CHRONAV_GRAPH``), as set for the agents themselves.

Exit codes, so scripts can tell "fix the change" from "fix the connection":
0 accepted (or listed/watched); 1 refused, by the agenda agent or already here because the
change cannot be valid (bad time, unreadable file: no round trip needed); 2 nothing was applied
because no system could be reached, the graph is empty, the agenda agent is missing or did not
answer in time (typer's own usage errors also exit 2); 130 interrupted while waiting.
"""

from __future__ import annotations

import json
import os
import sys
import time
import uuid
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

import typer

from tools.system.connection import (CONNECT_HELP, GRAPH_HELP, RUN_HELP, ConnectionProblem, Target, open_replica,
                              require_system, resolve_target)
from tools.system.runs import TOOL_AGENT_PREFIX, Role

DEFAULT_TIMEOUT_S = 10.0
SYNC_TIMEOUT_S = 5.0
POLL_S = 0.02

agenda_app = typer.Typer(help="List, change and watch the agenda of a running chronav system.",
                         no_args_is_help=True)


def register(app: typer.Typer) -> None:
    app.add_typer(agenda_app, name="agenda")


# ---------------------------------------------------------------------------------------------
# Errors: each carries the exit code the command ends with.
# ---------------------------------------------------------------------------------------------

class AgendaToolError(Exception):
    exit_code = 2


class LocalRefusal(AgendaToolError):
    """The change cannot be valid as written; refused before anything was sent."""

    exit_code = 1


class NoSystemError(AgendaToolError):
    """No system to talk to (unreachable router, empty graph, no agenda agent, no answer)."""

    exit_code = 2


# ---------------------------------------------------------------------------------------------
# Changes, validated here first so that mistakes need no round trip.
# ---------------------------------------------------------------------------------------------

def _pydantic_problems(exc: Any) -> str:
    """pydantic's errors in the user's words (scenes/yamlio.user_message), one per field."""
    from scenes.yamlio import user_message

    parts = []
    for error in exc.errors():
        where = ".".join(str(p) for p in error["loc"] if not (isinstance(p, str) and "function-" in p))
        message = user_message(error)
        parts.append(f"{where}: {message}" if where else message)
    return "; ".join(parts)


def split_participants(text: str | None) -> list[str]:
    """``"senior_1, therapist"`` -> ``["senior_1", "therapist"]`` (empty items dropped)."""
    return [p.strip() for p in (text or "").split(",") if p.strip()]


def add_change(object_name: str, start: str, end: str, *, name: str | None = None,
               participants: list[str] | None = None, activity_id: str | None = None,
               room: str | None = None, kind: str | None = None) -> dict[str, Any]:
    """The wire form of an ``add``; bad times, end before start and bad ids are refused here."""
    from pydantic import ValidationError

    from agents.lib.agenda.changes import AddChange
    from agents.lib.agenda.model import ActivitySpec

    fields: dict[str, Any] = {"name": name or object_name, "object": object_name, "start": start, "end": end,
                              "participants": tuple(participants or ()), "id": activity_id, "room": room,
                              "kind": kind}
    try:
        spec = ActivitySpec(**{k: v for k, v in fields.items() if v is not None})
    except ValidationError as exc:
        raise LocalRefusal(_pydantic_problems(exc)) from None
    return AddChange(activity=spec).model_dump(mode="json", exclude_none=True)


def _activity_id(text: str) -> str:
    if not text.strip():
        raise LocalRefusal("give the id of the activity (`chronav agenda list` shows them)")
    return text.strip()


def cancel_change(activity_id: str) -> dict[str, Any]:
    return {"op": "cancel", "id": _activity_id(activity_id)}


def move_change(activity_id: str, start: str | None, end: str | None) -> dict[str, Any]:
    """A ``move``: at least one new time; times are checked here, and their order when both are given."""
    from agents.lib.agenda.model import parse_when

    if start is None and end is None:
        raise LocalRefusal("say the new time: --start HH:MM and/or --end HH:MM (with only --start the "
                           "activity keeps its length)")
    values: dict[str, Any] = {}
    for label, text in (("start", start), ("end", end)):
        if text is not None:
            try:
                values[label] = parse_when(text)
            except ValueError as exc:
                raise LocalRefusal(f"--{label}: {exc}") from None
    if "start" in values and "end" in values and type(values["start"]) is type(values["end"]):
        with suppress(TypeError):  # naive vs aware datetimes: the agent decides
            if values["end"] <= values["start"]:
                raise LocalRefusal(f"--end {end!r} is not after --start {start!r}")
    change: dict[str, Any] = {"op": "move", "id": _activity_id(activity_id)}
    if start is not None:
        change["start"] = start
    if end is not None:
        change["end"] = end
    return change


AGENDA_FORMATS = {".ics": "ics", ".ical": "ics", ".yaml": "yaml", ".yml": "yaml"}


def load_change(path: Path, *, replace: bool) -> dict[str, Any]:
    """A ``load``: the file is read and parsed here, so its errors come back as file:line at once.

    Checks against the scene (unknown objects...) and the expansion for the sim day are the
    agent's: only it knows the scene and the date.
    """
    from agents.lib.agenda.model import AgendaSourceError
    from agents.lib.agenda.yaml_source import parse_agenda_text
    from scenes.errors import SourceError
    from scenes.files import read_text_bounded
    from scenes.limits import ICS_BYTES, YAML_BYTES

    fmt = AGENDA_FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise LocalRefusal(f"{path}: unknown agenda format {path.suffix or '(no suffix)'!r}; "
                           "use a .ics (iCalendar) or .yaml file")
    limit = ICS_BYTES if fmt == "ics" else YAML_BYTES
    try:   # a regular file within its size bound: /dev/zero, a FIFO or a directory is refused as such
        text = read_text_bounded(path, max_bytes=limit.value(), limit_env=limit.env, what=f"{fmt} agenda file")
    except SourceError as exc:
        raise LocalRefusal(str(exc)) from None
    try:
        parse_agenda_text(text, fmt, str(path))
    except AgendaSourceError as exc:
        raise LocalRefusal(f"{path} has errors, nothing was sent:\n{exc}") from None
    return {"op": "load", "mode": "replace" if replace else "merge", "format": fmt, "text": text,
            "source": path.name}


# ---------------------------------------------------------------------------------------------
# Talking to the system.
# ---------------------------------------------------------------------------------------------

def tool_agent_name() -> str:
    return f"{TOOL_AGENT_PREFIX}-{os.getpid()}"


def requested_by() -> str:
    """Who asked, as the agent logs it and the recording shows it."""
    import getpass

    try:
        user = getpass.getuser()
    except (KeyError, OSError):  # no passwd entry and no USER/LOGNAME (some containers)
        user = f"uid {os.getuid()}"
    return f"chronav agenda ({user}, pid {os.getpid()})"


def find_system(connect: list[str] | None, graph: str | None, run: str | None, role: Role) -> Target:
    """Where the system is (see tools/system/connection.py); problems exit 2."""
    try:
        return resolve_target(connect, graph, run, role=role)
    except ConnectionProblem as exc:
        raise NoSystemError(str(exc)) from None


@contextmanager
def open_system(target: Target, *, read_only: bool, need_agenda_agent: bool,
                timeout_s: float = SYNC_TIMEOUT_S) -> Iterator[Any]:
    """A replica of the running graph for the block; refuses (exit 2) when nobody is there or,
    for a change, when the agenda agent is missing."""
    from agents.world.vocabulary import AGENDA_AGENT
    try:
        with open_replica(target, agent=tool_agent_name(), read_only=read_only, timeout_s=timeout_s) as graph:
            others = require_system(graph, target)
            if need_agenda_agent and graph.replica is not None and AGENDA_AGENT not in others:
                where = f"; see {target.run_dir / 'logs' / 'agenda.log'}" if target.run_dir else ""
                raise NoSystemError(f"the agenda agent is not running in {target.describe()} (members: "
                                    f"{', '.join(others) or 'none'}){where}")
            yield graph
    except ConnectionProblem as exc:
        raise NoSystemError(str(exc)) from None


@dataclass(frozen=True)
class Answer:
    accepted: bool
    message: str
    request: str


def submit_change(graph: Any, change: dict[str, Any], *, timeout_s: float,
                  requester: str | None = None) -> Answer:
    """Insert the request, wait for the agent's answer, delete the request (always)."""
    from agents.world.vocabulary import AGENDA_REQUEST_PREFIX, NodeType, RequestAttr, RequestState, now_s
    name = f"{AGENDA_REQUEST_PREFIX}{uuid.uuid4().hex}"
    attrs: dict[str, Any] = {RequestAttr.CHANGE: json.dumps(change), RequestAttr.STATE: RequestState.PENDING,
                             RequestAttr.REQUESTED_BY: requester or requested_by()}
    asked_at = now_s(graph)
    if asked_at is not None:
        attrs[RequestAttr.REQUESTED_S] = asked_at
    node = graph.insert_node(type=NodeType.AGENDA_REQUEST, name=name, attrs=attrs)
    graph.flush()
    deadline = time.monotonic() + timeout_s
    try:
        while True:
            current = graph.get_node(node.id)
            state = None if current is None else current.attrs.get("state")
            if current is not None and state in RequestState.ANSWERED:
                return Answer(state == RequestState.ACCEPTED, str(current.attrs.get("message", "")), name)
            if current is None:
                raise NoSystemError(f"request {name} was deleted by someone else before an answer came")
            if time.monotonic() >= deadline:
                raise NoSystemError(f"no answer from the agenda agent within {timeout_s:g} s; the request was "
                                    "withdrawn. Is the system busy or stopping, or does its write policy "
                                    f"refuse {TOOL_AGENT_PREFIX}-* writers? Check with `chronav agenda list` "
                                    "whether the change was applied, or retry with a longer --timeout")
            time.sleep(POLL_S)
    finally:
        from dsr import DSRError

        with suppress(DSRError):
            graph.delete_node(node.id)
            graph.flush()


# ---------------------------------------------------------------------------------------------
# What `list` and `watch` show.
# ---------------------------------------------------------------------------------------------

def _clock_text(seconds: object) -> str:
    from scenes.clock import format_clock

    return format_clock(float(seconds)) if isinstance(seconds, (int, float)) else "?"


def _band_name(band: object) -> str:
    from agents.lib.agenda.chronemics import BAND_NAMES

    return BAND_NAMES[band] if isinstance(band, int) and 0 <= band < len(BAND_NAMES) else "?"


def object_row(node: Any) -> dict[str, Any]:
    r = node.attrs.get("R")
    return {"name": node.name, "R": float(r) if isinstance(r, (int, float)) else None,
            "R_band": node.attrs.get("R_band"), "band": _band_name(node.attrs.get("R_band")),
            "active": bool(node.attrs.get("active", False))}


def activity_row(node: Any, objects: Mapping[str, dict[str, Any]]) -> dict[str, Any]:
    a = node.attrs
    obj = objects.get(str(a.get("object")))
    return {"id": a.get("activity_id", node.name.removeprefix("activity/")), "name": a.get("name", ""),
            "object": a.get("object", ""), "room": a.get("room") or None,
            "start": _clock_text(a.get("start_s")), "end": _clock_text(a.get("end_s")),
            "start_s": a.get("start_s"), "end_s": a.get("end_s"), "state": a.get("state", "?"),
            "participants": list(a.get("participants", [])), "source": a.get("source", ""),
            "object_R": None if obj is None else obj["R"]}


def snapshot(graph: Any) -> dict[str, Any]:
    """Today's activities (by start) and every object's current R: what `list --json` prints."""
    from agents.world.vocabulary import NodeType, now_s
    objects = {n.name: object_row(n) for n in graph.nodes_of_type(NodeType.OBJECT)}
    rows = [activity_row(n, objects) for n in graph.nodes_of_type(NodeType.ACTIVITY)]
    rows.sort(key=lambda r: (float(r["start_s"]) if isinstance(r["start_s"], (int, float)) else 0.0, r["id"]))
    now = now_s(graph)
    return {"graph": graph.graph_name, "now_s": now, "now": None if now is None else _clock_text(now),
            "activities": rows, "objects": sorted(objects.values(), key=lambda o: o["name"])}


def print_snapshot(data: dict[str, Any], out: TextIO) -> None:
    """A table on a terminal; on a pipe or file, a plain layout wrapped between words (tools/plain.py)."""
    from rich.console import Console
    from rich.table import Table
    from rich.text import Text

    from scenes.names import shown
    from tools.plain import is_plain, plural

    def cell(value: object, limit: int = 120) -> Text:
        # Names come from other people's files and commands: never markup, never terminal escapes.
        return Text(shown(value, limit))

    console = Console(file=out, highlight=False, soft_wrap=True)
    heading = f"agenda of {shown(data['graph'], 80)} at {data['now'] or '?'}: {plural(len(data['activities']), 'activity', 'activities')}"
    objects = ", ".join(_object_text(o) for o in data["objects"])
    if is_plain(console):
        _print_plain_snapshot(console, heading, data["activities"], shown(objects or "none yet", 10_000))
        return
    table = Table(title=Text(heading), title_justify="left")
    for column in ("id", "name", "object", "start", "end", "state", "participants", "R now"):
        # Ids, objects, times and states are single tokens: they keep their width, text columns wrap.
        wraps = column in ("name", "participants")
        table.add_column(column, overflow="fold", no_wrap=not wraps)
    for row in data["activities"]:
        r = row["object_R"]
        table.add_row(cell(row["id"]), cell(row["name"]), cell(row["object"]), cell(row["start"]), cell(row["end"]),
                      cell(row["state"]), cell(", ".join(map(str, row["participants"])), 4_000),
                      "-" if r is None else f"{r:.2f}")
    console.print(table)
    console.print(shown(f"objects: {objects or 'none yet'}", 10_000), markup=False)


def _print_plain_snapshot(console: Any, heading: str, activities: list[dict[str, Any]], objects: str) -> None:
    """Two or three lines per activity: when, state and id; then its object, R and participants,
    wrapped between words at the console's width (never a name cut in two)."""
    from scenes.names import shown
    from tools.plain import console_width, print_lines, wrapped

    width = console_width(console)
    lines = wrapped(heading, width, indent="  ")
    for row in activities:
        name = f" ({shown(row['name'], 120)})" if row["name"] and row["name"] != row["id"] else ""
        lines += wrapped(f"{row['start']}-{row['end']} {shown(row['state'], 40)}: {shown(row['id'], 120)}{name}",
                         width, first="  ", indent="      ")
        r = row["object_R"]
        detail = f"on {shown(row['object'], 120)}, R now {'-' if r is None else f'{r:.2f}'}"
        if row["participants"]:
            detail += "; participants: " + ", ".join(shown(p, 120) for p in row["participants"])
        lines += wrapped(detail, width, first="      ", indent="      ")
    lines += wrapped(f"objects: {objects}", width, indent="  ")
    print_lines(console, lines)


def _r_text(row: dict[str, Any]) -> str:
    """``3.37 (dark_orange, activity running)``: R, its colour band, whether an activity runs."""
    r = "?" if row["R"] is None else f"{row['R']:.2f}"
    return f"{r} ({row['band']}{', activity running' if row['active'] else ''})"


def _object_text(row: dict[str, Any]) -> str:
    return f"{row['name']} R={_r_text(row)}"


class ChangeWatcher:
    """Turns DSR signals into one line per agenda change (activities, R steps, answered requests).

    R creeps every sim second while an activity approaches; a line is printed when it moved by
    ``r_step`` since the last line for that object, or when its band or running flag changed.
    """

    def __init__(self, graph: Any, *, r_step: float, as_json: bool, out: TextIO, limit: int = 0) -> None:
        from agents.world.vocabulary import NodeType
        self.graph, self.r_step, self.as_json, self.out, self.limit = graph, r_step, as_json, out, limit
        self.lines = 0
        self.activities: dict[int, dict[str, Any]] = {n.id: dict(n.attrs) for n in graph.nodes_of_type(NodeType.ACTIVITY)}
        self.objects: dict[int, dict[str, Any]] = {n.id: object_row(n) for n in graph.nodes_of_type(NodeType.OBJECT)}
        self.finished = False

    def connect(self) -> None:
        self.graph.connect("node_added", self.on_node)
        self.graph.connect("node_updated", self.on_node)
        self.graph.connect("node_deleted", self.on_deleted)

    @property
    def done(self) -> bool:
        return bool(self.limit) and self.lines >= self.limit

    def emit(self, kind: str, text: str, **fields: Any) -> None:
        from agents.world.vocabulary import now_s
        if self.done:
            return
        now = now_s(self.graph)
        if self.as_json:  # JSON escapes control characters itself
            line = json.dumps({"t_s": now, "time": _clock_text(now), "kind": kind, **fields, "text": text})
        else:
            from scenes.names import shown

            line = f"{_clock_text(now)} {shown(text, 2_000)}"
        self.out.write(line + "\n")
        self.out.flush()
        self.lines += 1

    def on_node(self, node: Any, changed: Any = None) -> None:
        from agents.world.vocabulary import NodeType
        if node.type == NodeType.ACTIVITY:
            self._activity(node)
        elif node.type == NodeType.OBJECT:
            self._object(node)
        elif node.type == NodeType.AGENDA_REQUEST:
            self._request(node, changed)
        elif node.type == NodeType.CLOCK and node.attrs.get("finished") and not self.finished:
            self.finished = True
            self.emit("clock", "the sim day is over (clock finished)")

    def _activity(self, node: Any) -> None:
        new, old = dict(node.attrs), self.activities.get(node.id)
        self.activities[node.id] = new
        aid = new.get("activity_id", node.name)
        times = f"{_clock_text(new.get('start_s'))}-{_clock_text(new.get('end_s'))}"
        if old is None:
            self.emit("activity", f"activity {aid} added: {new.get('object')} {times} {new.get('state')} "
                      f"({new.get('name')})", event="added", activity=new)
            return
        if (old.get("start_s"), old.get("end_s")) != (new.get("start_s"), new.get("end_s")):
            self.emit("activity", f"activity {aid} moved: {_clock_text(old.get('start_s'))}-"
                      f"{_clock_text(old.get('end_s'))} -> {times}", event="moved", activity=new)
        if old.get("state") != new.get("state"):
            self.emit("activity", f"activity {aid} {old.get('state')} -> {new.get('state')}",
                      event="state", activity=new)
        other = {k for k in set(old) | set(new) if old.get(k) != new.get(k)} - {"start_s", "end_s", "state"}
        if other:
            self.emit("activity", f"activity {aid} changed: " + ", ".join(f"{k}={new.get(k)!r}" for k in sorted(other)),
                      event="changed", activity=new)

    def on_deleted(self, node_id: int) -> None:
        old = self.activities.pop(node_id, None)
        if old is not None:
            self.emit("activity", f"activity {old.get('activity_id')} removed from the agenda", event="removed",
                      activity=old)
        self.objects.pop(node_id, None)

    def _object(self, node: Any) -> None:
        new, old = object_row(node), self.objects.get(node.id)
        if new["R"] is None:
            return
        if old is not None and old["R"] is not None and abs(new["R"] - old["R"]) < self.r_step and (
                old["R_band"], old["active"]) == (new["R_band"], new["active"]):
            return
        self.objects[node.id] = new
        before = "?" if old is None or old["R"] is None else f"{old['R']:.2f}"
        self.emit("object", f"object {new['name']} R {before} -> {_r_text(new)}",
                  event="R", object=new)

    def _request(self, node: Any, changed: Any) -> None:
        from agents.world.vocabulary import RequestState
        state = node.attrs.get("state")
        if state in RequestState.ANSWERED and (changed is None or "state" in changed):
            message = str(node.attrs.get("message", ""))
            # The agent's refusals already begin "refused: "; the line says it once.
            self.emit("request", f"request from {node.attrs.get('requested_by', '?')} {state}: "
                      f"{message.removeprefix(f'{state}: ')}", event=state, request=node.name)


# ---------------------------------------------------------------------------------------------
# Commands.
# ---------------------------------------------------------------------------------------------

RUN_CHECK_S = 1.0


def system_ended(graph: Any, target: Target) -> str | None:
    """Why there is nothing left to watch (the run ended, or every agent left the graph), or None.

    Why: a watch that outlives its run waited silently forever; the launcher's end (result.json,
    or its process gone) and the agents' liveliness tokens both say the system is gone."""
    from tools.system.connection import members
    from tools.system.runs import run_is_alive

    if target.run_dir is not None and not run_is_alive(target.run_dir):
        return f"run {target.run_dir.name} has ended"
    present = members(graph, timeout_s=RUN_CHECK_S)
    if present is not None and not [m for m in present if m != graph.agent]:
        return f"no agent is left in {target.describe()}: the system has stopped"
    return None


@dataclass(frozen=True)
class Connection:
    connect: list[str] | None
    graph: str | None
    run: str | None


TIMEOUT_HELP = "Seconds to wait for the agenda agent's answer."


def _fail(command: str, exc: AgendaToolError) -> None:
    from scenes.names import shown

    typer.echo("\n".join(shown(line, 2_000) for line in f"chronav agenda {command}: {exc}".splitlines()), err=True)
    raise typer.Exit(exc.exit_code)


def _change(command: str, build: Callable[[], dict[str, Any]], conn: Connection, timeout: float,
            as_json: bool) -> None:
    """Build the change (local checks), send it, print the answer, exit 0/1/2."""
    from dsr.process import exit_on_sigterm

    exit_on_sigterm()
    try:
        change = build()
        address = find_system(conn.connect, conn.graph, conn.run, "tool")
        with open_system(address, read_only=False, need_agenda_agent=True) as graph:
            answer = submit_change(graph, change, timeout_s=timeout)
    except AgendaToolError as exc:
        _fail(command, exc)
        return
    except KeyboardInterrupt:
        typer.echo(f"chronav agenda {command}: interrupted; a request already sent was withdrawn (check "
                   "`chronav agenda list`: the agent may have applied it)", err=True)
        raise typer.Exit(130) from None
    if as_json:
        sent = {k: v for k, v in change.items() if k != "text"}
        typer.echo(json.dumps({"accepted": answer.accepted, "message": answer.message, "request": answer.request,
                               "graph": address.graph, "change": sent}))
    if answer.accepted:
        if not as_json:
            from scenes.names import shown

            typer.echo(f"accepted: {shown(answer.message, 2_000)}")
        return
    from scenes.names import shown

    typer.echo("\n".join(shown(line, 2_000) for line in f"chronav agenda {command}: {answer.message}".splitlines()),
               err=True)
    raise typer.Exit(1)


@agenda_app.command("add")
def add_command(
    object_name: str = typer.Argument(..., metavar="OBJECT", help="object of the scene, e.g. tv"),
    start: str = typer.Argument(..., metavar="START", help="HH:MM (or an ISO date-time on the sim day)"),
    end: str = typer.Argument(..., metavar="END", help="HH:MM, after START"),
    name: str = typer.Option(None, "--name", help="what staff call it (default: the object's name)"),
    participants: str = typer.Option(None, "--participants", help="people's names, comma-separated"),
    activity_id: str = typer.Option(None, "--id", help="its id (default: derived, e.g. tv-1100)"),
    room: str = typer.Option(None, "--room", help="room of the activity"),
    kind: str = typer.Option(None, "--kind", help="free text: therapy, serious_game, meal..."),
    connect: list[str] = typer.Option(None, "--connect", help=CONNECT_HELP),
    graph: str = typer.Option(None, "--graph", help=GRAPH_HELP),
    run: str = typer.Option(None, "--run", help=RUN_HELP),
    timeout: float = typer.Option(DEFAULT_TIMEOUT_S, "--timeout", help=TIMEOUT_HELP),
    as_json: bool = typer.Option(False, "--json", help="print the answer as one JSON object"),
) -> None:
    """Add an activity on OBJECT from START to END (today, on the sim clock)."""
    _change("add", lambda: add_change(object_name, start, end, name=name,
                                      participants=split_participants(participants), activity_id=activity_id,
                                      room=room, kind=kind),
            Connection(connect, graph, run), timeout, as_json)


@agenda_app.command("cancel")
def cancel_command(
    activity_id: str = typer.Argument(..., metavar="ID", help="activity id, as `chronav agenda list` shows"),
    connect: list[str] = typer.Option(None, "--connect", help=CONNECT_HELP),
    graph: str = typer.Option(None, "--graph", help=GRAPH_HELP),
    run: str = typer.Option(None, "--run", help=RUN_HELP),
    timeout: float = typer.Option(DEFAULT_TIMEOUT_S, "--timeout", help=TIMEOUT_HELP),
    as_json: bool = typer.Option(False, "--json", help="print the answer as one JSON object"),
) -> None:
    """Cancel an activity (it stays on the agenda, marked cancelled, and no longer raises R)."""
    _change("cancel", lambda: cancel_change(activity_id), Connection(connect, graph, run), timeout, as_json)


@agenda_app.command("move")
def move_command(
    activity_id: str = typer.Argument(..., metavar="ID", help="activity id, as `chronav agenda list` shows"),
    start: str = typer.Option(None, "--start", help="new start HH:MM (alone: the activity keeps its length)"),
    end: str = typer.Option(None, "--end", help="new end HH:MM (alone: the activity keeps its start)"),
    connect: list[str] = typer.Option(None, "--connect", help=CONNECT_HELP),
    graph: str = typer.Option(None, "--graph", help=GRAPH_HELP),
    run: str = typer.Option(None, "--run", help=RUN_HELP),
    timeout: float = typer.Option(DEFAULT_TIMEOUT_S, "--timeout", help=TIMEOUT_HELP),
    as_json: bool = typer.Option(False, "--json", help="print the answer as one JSON object"),
) -> None:
    """Move an activity to a new start and/or end, on the same day."""
    _change("move", lambda: move_change(activity_id, start, end), Connection(connect, graph, run), timeout,
            as_json)


@agenda_app.command("load")
def load_command(
    file: Path = typer.Argument(..., metavar="FILE", help="a .ics or .yaml agenda file"),
    replace: bool = typer.Option(False, "--replace/--merge",
                                 help="replace the whole day's agenda, or merge (same id -> replaced)"),
    connect: list[str] = typer.Option(None, "--connect", help=CONNECT_HELP),
    graph: str = typer.Option(None, "--graph", help=GRAPH_HELP),
    run: str = typer.Option(None, "--run", help=RUN_HELP),
    timeout: float = typer.Option(DEFAULT_TIMEOUT_S, "--timeout", help=TIMEOUT_HELP),
    as_json: bool = typer.Option(False, "--json", help="print the answer as one JSON object"),
) -> None:
    """Load an agenda file into today's agenda: all of it, or nothing if any activity is wrong."""
    _change("load", lambda: load_change(file, replace=replace), Connection(connect, graph, run), timeout, as_json)


@agenda_app.command("list")
def list_command(
    connect: list[str] = typer.Option(None, "--connect", help=CONNECT_HELP),
    graph: str = typer.Option(None, "--graph", help=GRAPH_HELP),
    run: str = typer.Option(None, "--run", help=RUN_HELP),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
) -> None:
    """Today's activities with their state, times and object, and every object's current R."""
    from dsr.process import exit_on_sigterm

    exit_on_sigterm()
    try:
        address = find_system(connect, graph, run, "reader")
        with open_system(address, read_only=True, need_agenda_agent=False) as replica:
            data = snapshot(replica)
    except AgendaToolError as exc:
        _fail("list", exc)
        return
    if as_json:
        typer.echo(json.dumps(data))
    else:
        print_snapshot(data, sys.stdout)


@agenda_app.command("watch")
def watch_command(
    count: int = typer.Option(0, "--count", min=0, help="stop after this many lines (0: no limit)"),
    timeout: float = typer.Option(0.0, "--timeout", min=0.0, help="stop after this many seconds (0: Ctrl-C)"),
    r_step: float = typer.Option(0.1, "--r-step", min=0.0, help="print an object's R when it moved this much"),
    connect: list[str] = typer.Option(None, "--connect", help=CONNECT_HELP),
    graph: str = typer.Option(None, "--graph", help=GRAPH_HELP),
    run: str = typer.Option(None, "--run", help=RUN_HELP),
    as_json: bool = typer.Option(False, "--json", help="one JSON object per line"),
) -> None:
    """Follow the agenda live: one line per activity change, R step or answered request."""
    from agents.world.vocabulary import now_s
    from dsr.process import exit_on_sigterm
    from tools.plain import plural

    exit_on_sigterm()
    try:
        address = find_system(connect, graph, run, "reader")
        with open_system(address, read_only=True, need_agenda_agent=False) as replica:
            watcher = ChangeWatcher(replica, r_step=r_step, as_json=as_json, out=sys.stdout, limit=count)
            watcher.connect()
            typer.echo(f"watching the agenda of {address.describe()} at {_clock_text(now_s(replica))}: "
                       f"{plural(len(watcher.activities), 'activity', 'activities')} (ends with the run, or "
                       "Ctrl-C)", err=True)
            deadline = time.monotonic() + timeout if timeout > 0 else None
            next_check = time.monotonic() + RUN_CHECK_S
            while not watcher.done and (deadline is None or time.monotonic() < deadline):
                replica.dispatch(timeout=0.1)
                if time.monotonic() >= next_check:
                    ended = system_ended(replica, address)
                    if ended:
                        typer.echo(f"watch ends: {ended}", err=True)
                        return
                    next_check = time.monotonic() + RUN_CHECK_S
    except AgendaToolError as exc:
        _fail("watch", exc)
    except KeyboardInterrupt:
        return

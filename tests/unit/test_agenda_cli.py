"""`chronav agenda`: argument checks, messages and exit codes, against a real agenda agent.

Why a real in-process router and the real AgendaAgent (stepped on a thread) instead of a fake:
the tool's contract is the request protocol of agents/agenda/agent.py, and the messages it must
relay (unknown object, unknown id) are the agent's own; a fake would only test itself.  Each
test gets its own graph name, so the tests share the router but never state.
"""

from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from io import StringIO
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from agents.agenda.agent import AgendaAgent
from agents.runtime.config import AgentConfig
from agents.runtime.recording import Recorder
from agents.lib.agenda.chronemics import ChronemicsParams, r_of_t
from agents.world.dsr_writers import R_DECIMALS
from agents.lib.agenda.model import ActivityWindow
from agents.world.dsr_writers import object_attrs
from agents.world.vocabulary import NodeType
from dsr import DSRGraph, ZenohSettings, join
from scenes.loader import load_scene
from tests.support import REPO_ROOT, free_port, wait_until
from tools import agenda as tool
from tools.cli import app
from tools.system.runs import RunSecurity, prepare_run_security, write_connect_file

SCENE = REPO_ROOT / "tests" / "data" / "agenda_live.yaml"
NOW_S = 9 * 3600 + 5 * 60.0          # 09:05 on the sim clock
START_S, END_S = 9 * 3600 + 8 * 60.0, 9 * 3600 + 40 * 60.0
runner = CliRunner()
_graph_numbers = itertools.count()


def expected_r(start_s: float = START_S, end_s: float = END_S, now_s: float = NOW_S) -> float:
    """R(t) of the tv as the agenda agent publishes it (rounded to R_DECIMALS)."""
    return round(r_of_t(now_s, [ActivityWindow(object="tv", start_s=start_s, end_s=end_s, cancelled=False)],
                        ChronemicsParams()), R_DECIMALS)


# ---------------------------------------------------------------------------------------------
# A tiny live system: router + a world replica (clock, objects) + the real agenda agent.
# ---------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def router() -> Iterator[str]:
    import zenoh

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    session = zenoh.open(ZenohSettings(mode="router", listen=[endpoint]).to_zenoh_config())
    try:
        yield endpoint
    finally:
        session.close()


def _client(endpoint: str, security: RunSecurity | None = None, agent: str = "") -> ZenohSettings:
    if security is None:
        return ZenohSettings(connect=[endpoint])
    identity = security.agents[agent]
    return ZenohSettings(connect=[endpoint], user=identity.user, password=identity.password)


@dataclass
class LiveSystem:
    endpoint: str
    graph: str
    world: DSRGraph
    errors: list[BaseException] = field(default_factory=list)
    security: RunSecurity | None = None

    @property
    def env(self) -> dict[str, str]:
        return {"CHRONAV_ZENOH_CONNECT": self.endpoint, "CHRONAV_GRAPH": self.graph}

    def invoke(self, *args: str) -> Any:
        return runner.invoke(app, ["agenda", *args], env=self.env)

    def tv_r(self) -> float:
        return float(self.world.get_node_by_name("tv").attrs.get("R", -1.0))

    def requests(self) -> list[Any]:
        return self.world.nodes_of_type(NodeType.AGENDA_REQUEST)


def _populate_world(world: DSRGraph) -> None:
    """What sim_robot and object_recognition would have written: the clock and the TV."""
    scene = load_scene(SCENE).scene
    root = world.insert_node(type="world", name="world", attrs={})
    world.insert_node(type="clock", name="clock", attrs={"now_s": NOW_S})
    for obj in scene.objects:
        node = world.insert_node(type="object", name=obj.name, attrs=object_attrs(obj))
        world.insert_or_assign_edge(root.id, node.id, "RT",
                                    attrs={"x": obj.pose.x, "y": obj.pose.y, "theta": obj.pose.theta})
    world.flush()


@pytest.fixture
def world_only(router: str) -> Iterator[LiveSystem]:
    """A graph with a clock and the TV, but no agenda agent."""
    graph = f"agenda_cli_{os.getpid()}_{next(_graph_numbers)}"
    with join("sim_robot", graph=graph, settings=_client(router)) as world:
        _populate_world(world)
        yield LiveSystem(router, graph, world)


def _agent_loop(system: LiveSystem, ready: threading.Event, stop: threading.Event, step: bool) -> None:
    try:
        agent = AgendaAgent(AgentConfig(name="agenda", scene=SCENE, graph=system.graph))
        with join("agenda", graph=system.graph, settings=_client(system.endpoint, system.security, "agenda")) as graph:
            agent.setup(graph, Recorder("agenda", None, None))
            ready.set()
            while not stop.wait(0.01):
                if step:
                    agent.step()
                graph.dispatch(0.0)
    except BaseException as exc:  # noqa: BLE001 - reported by the fixture
        system.errors.append(exc)
        ready.set()


def _with_agent(system: LiveSystem, step: bool) -> Iterator[LiveSystem]:
    ready, stop = threading.Event(), threading.Event()
    thread = threading.Thread(target=_agent_loop, args=(system, ready, stop, step), daemon=True)
    thread.start()
    try:
        assert ready.wait(10), "the agenda agent did not start"
        assert not system.errors, system.errors
        wait_until(lambda: system.world.get_node_by_name("agenda") is not None, 5, message="agenda node")
        if step:
            wait_until(lambda: system.tv_r() == pytest.approx(1.5), 5, message="R_min on the TV")
        yield system
    finally:
        stop.set()
        thread.join(10)
    assert not system.errors, system.errors


@pytest.fixture
def live(world_only: LiveSystem) -> Iterator[LiveSystem]:
    """The world plus the real agenda agent answering requests."""
    yield from _with_agent(world_only, step=True)


@pytest.fixture
def silent(world_only: LiveSystem) -> Iterator[LiveSystem]:
    """An 'agenda' member that never answers (a hung agent)."""
    yield from _with_agent(world_only, step=False)


# ---------------------------------------------------------------------------------------------
# Changes through the agent.
# ---------------------------------------------------------------------------------------------

def test_add_prints_the_answer_and_list_json_shows_activity_and_r(live: LiveSystem) -> None:
    result = live.invoke("add", "tv", "09:08", "09:40", "--name", "Serious game",
                         "--participants", "senior_1, therapist")
    assert result.exit_code == 0, result.output
    assert result.stdout == "accepted: add: tv-0908 tv 09:08:00-09:40:00 upcoming\n"
    wait_until(lambda: live.tv_r() == pytest.approx(expected_r()), 5, message="R raised")
    # the delete travels tool -> router -> this replica, independently of the agenda's R write
    wait_until(lambda: not live.requests(), 5, message="the tool deletes its request once answered")

    listed = live.invoke("list", "--json")
    assert listed.exit_code == 0, listed.output
    data = json.loads(listed.stdout)
    assert data["graph"] == live.graph and data["now"] == "09:05:00" and data["now_s"] == NOW_S
    (row,) = data["activities"]
    assert {k: row[k] for k in ("id", "name", "object", "start", "end", "state", "participants")} == {
        "id": "tv-0908", "name": "Serious game", "object": "tv", "start": "09:08:00", "end": "09:40:00",
        "state": "upcoming", "participants": ["senior_1", "therapist"]}
    assert row["object_R"] == pytest.approx(expected_r())
    (obj,) = data["objects"]
    assert obj["name"] == "tv" and obj["R"] == pytest.approx(expected_r()) and obj["band"] == "dark_orange"
    assert obj["active"] is False


def test_list_table_shows_times_state_and_r(live: LiveSystem) -> None:
    assert live.invoke("add", "tv", "09:08", "09:40").exit_code == 0
    wait_until(lambda: live.tv_r() > 3.0, 5, message="R raised")
    # Piped (CliRunner is not a terminal) at 80 columns: the plain layout, names whole (issue 39).
    result = runner.invoke(app, ["agenda", "list"], env={**live.env, "COLUMNS": "80"})
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0] == f"agenda of {live.graph} at 09:05:00: 1 activity"
    assert lines[1:3] == ["  09:08:00-09:40:00 upcoming: tv-0908 (tv)", f"      on tv, R now {expected_r():.2f}"]
    assert f"objects: tv R={expected_r():.2f} (dark_orange)" in result.stdout
    assert all(len(line) <= 80 for line in lines), lines


def test_unknown_object_is_refused_naming_it_and_the_known_ones(live: LiveSystem) -> None:
    result = live.invoke("add", "sofa", "09:08", "09:40")
    assert result.exit_code == 1
    assert result.stdout == ""
    assert "no object named 'sofa'" in result.stderr and "known objects: tv" in result.stderr
    assert live.world.nodes_of_type("activity") == []
    wait_until(lambda: not live.requests(), 5, message="request withdrawn")


def test_cancel_of_an_unknown_id_is_refused_listing_the_ids(live: LiveSystem) -> None:
    assert live.invoke("add", "tv", "09:08", "09:40").exit_code == 0
    result = live.invoke("cancel", "tv-1100")
    assert result.exit_code == 1
    assert "no activity with id 'tv-1100'" in result.stderr and "(ids: tv-0908)" in result.stderr


def test_move_then_cancel(live: LiveSystem) -> None:
    assert live.invoke("add", "tv", "09:08", "09:40").exit_code == 0
    moved = live.invoke("move", "tv-0908", "--start", "09:20", "--json")
    assert moved.exit_code == 0, moved.output
    answer = json.loads(moved.stdout)
    assert answer["accepted"] is True and answer["message"] == "move: tv-0908 tv 09:20:00-09:52:00 upcoming"
    assert answer["change"] == {"op": "move", "id": "tv-0908", "start": "09:20"}
    wait_until(lambda: live.tv_r() == pytest.approx(expected_r(START_S + 720, END_S + 720)), 5, message="R moved")

    cancelled = live.invoke("cancel", "tv-0908")
    assert cancelled.exit_code == 0, cancelled.output
    assert cancelled.stdout == "accepted: cancel: tv-0908 tv 09:20:00-09:52:00 cancelled\n"
    wait_until(lambda: live.tv_r() == pytest.approx(1.5), 5, message="R back to R_min")
    again = live.invoke("cancel", "tv-0908")
    assert again.exit_code == 1 and "already cancelled" in again.stderr


def test_load_merge_and_replace(live: LiveSystem, tmp_path: Path) -> None:
    day = tmp_path / "day.yaml"
    day.write_text('activities:\n  - {id: game, name: Game, object: tv, start: "09:30", end: "10:00"}\n')
    assert live.invoke("add", "tv", "09:08", "09:40").exit_code == 0
    merged = live.invoke("load", str(day))
    assert merged.exit_code == 0, merged.output
    assert merged.stdout == "accepted: load: game tv 09:30:00-10:00:00 upcoming\n"
    wait_until(lambda: len(live.world.nodes_of_type("activity")) == 2, 5, message="two activities")
    replaced = live.invoke("load", str(day), "--replace")
    assert replaced.exit_code == 0, replaced.output
    assert "removed tv-0908" in replaced.stdout
    wait_until(lambda: [n.attrs["activity_id"] for n in live.world.nodes_of_type("activity")] == ["game"], 5,
               message="only the file's activity")

    wrong_object = tmp_path / "sofa.yaml"
    wrong_object.write_text('activities:\n  - {name: Bingo, object: sofa, start: "09:30", end: "10:00"}\n')
    refused = live.invoke("load", str(wrong_object))
    assert refused.exit_code == 1
    assert "sofa.yaml:2" in refused.stderr and "no object named 'sofa'" in refused.stderr


# ---------------------------------------------------------------------------------------------
# Refused before sending: the exit code is 1 even with no system at all.
# ---------------------------------------------------------------------------------------------

@pytest.fixture
def nobody_env() -> dict[str, str]:
    return {"CHRONAV_ZENOH_CONNECT": f"tcp/127.0.0.1:{free_port()}", "CHRONAV_GRAPH": "nobody"}


@pytest.mark.parametrize(("args", "message"), [
    (["add", "tv", "25:00", "26:00"], "start: '25:00' is not a valid clock time (00:00 to 24:00)"),
    (["add", "tv", "10:00", "09:00"], "end: end '09:00' is not after start '10:00'"),
    (["add", "tv", "10", "11:00"], "start: '10' is not a time: use HH:MM"),
    (["add", "tv", "09:00", "10:00", "--id", "my game"], "id: an id is one word without spaces, got 'my game'"),
    (["move", "tv-0908"], "say the new time: --start HH:MM and/or --end HH:MM"),
    (["move", "tv-0908", "--start", "10:00", "--end", "09:30"], "--end '09:30' is not after --start '10:00'"),
    (["move", "tv-0908", "--end", "half past"], "--end: 'half past' is not a time"),
])
def test_invalid_changes_are_refused_locally(nobody_env: dict[str, str], args: list[str], message: str) -> None:
    result = runner.invoke(app, ["agenda", *args], env=nobody_env)
    assert result.exit_code == 1, result.output
    assert message in result.stderr
    assert result.stderr.startswith(f"chronav agenda {args[0]}: ")


def test_load_reports_file_errors_with_lines_before_sending(nobody_env: dict[str, str], tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text('activities:\n  - name: Bingo\n    object: tv\n    start: "25:00"\n    end: "12:00"\n'
                   '  - {name: Quiz, objet: tv, start: "10:00", end: "11:00"}\n')
    result = runner.invoke(app, ["agenda", "load", str(bad)], env=nobody_env)
    assert result.exit_code == 1
    assert f"{bad}:4:5: activities[0].start: '25:00' is not a valid clock time" in result.stderr
    assert f"{bad}:6:18: activities[1].objet: unknown key 'objet' (did you mean 'object'?)" in result.stderr

    ics = tmp_path / "bad.ics"
    ics.write_text((REPO_ROOT / "tests" / "data" / "agenda_bad.ics").read_text())
    result = runner.invoke(app, ["agenda", "load", str(ics)], env=nobody_env)
    assert result.exit_code == 1 and f"{ics}:4: UID=no-object@centre.example: no object" in result.stderr

    for path, message in ((tmp_path / "day.txt", "unknown agenda format '.txt'"),
                          (tmp_path / "missing.yaml", "no such file")):
        if path.suffix == ".txt":
            path.write_text("x")
        result = runner.invoke(app, ["agenda", "load", str(path)], env=nobody_env)
        assert result.exit_code == 1 and message in result.stderr


# ---------------------------------------------------------------------------------------------
# No system to talk to: exit 2 and a message saying what to check.
# ---------------------------------------------------------------------------------------------

def test_unreachable_router_exits_2(nobody_env: dict[str, str]) -> None:
    endpoint = nobody_env["CHRONAV_ZENOH_CONNECT"]
    for args in (["add", "tv", "09:08", "09:40"], ["list"], ["watch", "--timeout", "1"]):
        result = runner.invoke(app, ["agenda", *args], env=nobody_env)
        assert result.exit_code == 2, result.output
        assert f"cannot reach a chronav system: nothing listens at {endpoint} (from CHRONAV_ZENOH_CONNECT" \
            in result.stderr
        assert "chronav launch" in result.stderr and "--run latest" in result.stderr


def test_empty_graph_exits_2(router: str) -> None:
    result = runner.invoke(app, ["agenda", "list", "--connect", router, "--graph", "no_such_run"])
    assert result.exit_code == 2
    assert "graph 'no_such_run'" in result.stderr and "nobody is there" in result.stderr


def test_missing_agenda_agent_exits_2_but_list_works(world_only: LiveSystem) -> None:
    result = world_only.invoke("cancel", "tv-0908")
    assert result.exit_code == 2
    assert "the agenda agent is not running" in result.stderr and "(members: sim_robot)" in result.stderr
    assert not world_only.requests(), "nothing is written when no agent can answer"
    listed = world_only.invoke("list", "--json")
    assert listed.exit_code == 0 and json.loads(listed.stdout)["activities"] == []


def test_no_answer_times_out_exits_2_and_withdraws_the_request(silent: LiveSystem) -> None:
    result = silent.invoke("add", "tv", "09:08", "09:40", "--timeout", "0.5")
    assert result.exit_code == 2
    assert "no answer from the agenda agent within 0.5 s; the request was withdrawn" in result.stderr
    wait_until(lambda: not silent.requests(), 5, message="request deleted")


# ---------------------------------------------------------------------------------------------
# Finding the system: --run latest of this user, with the run's credentials.
# ---------------------------------------------------------------------------------------------

@pytest.fixture
def secured_run(tmp_path: Path) -> Iterator[LiveSystem]:
    """A run as `chronav launch` leaves it: a router requiring the run's credentials and ACL, the
    world and the agenda agent each with their own user, and the owner-only connect file."""
    import zenoh

    graph = f"agenda_cli_secured_{os.getpid()}"
    run_dir = tmp_path / "recordings" / graph
    security = prepare_run_security(run_dir, graph, ("sim_robot", "agenda"))
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    router = zenoh.open(ZenohSettings(mode="router", listen=[endpoint], credentials_file=security.credentials_file,
                                      acl_file=security.acl_file).to_zenoh_config())
    try:
        write_connect_file(run_dir, run_id=graph, endpoint=endpoint, graph=graph, security=security)
        with join("sim_robot", graph=graph, settings=_client(endpoint, security, "sim_robot")) as world:
            _populate_world(world)
            yield from _with_agent(LiveSystem(endpoint, graph, world, security=security), step=True)
    finally:
        router.close()


def test_run_latest_joins_with_the_runs_credentials(secured_run: LiveSystem, tmp_path: Path) -> None:
    env = {"CHRONAV_RUNS": str(tmp_path / "recordings"),
           "CHRONAV_ZENOH_CONNECT": f"tcp/127.0.0.1:{free_port()}", "CHRONAV_GRAPH": "wrong"}
    result = runner.invoke(app, ["agenda", "add", "tv", "09:08", "09:40", "--run", "latest", "--json"], env=env)
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["graph"] == secured_run.graph and json.loads(result.stdout)["accepted"]
    listed = runner.invoke(app, ["agenda", "list", "--run", "latest", "--json"], env=env)
    assert listed.exit_code == 0 and [a["id"] for a in json.loads(listed.stdout)["activities"]] == ["tv-0908"]
    # No option and no CHRONAV_ZENOH_*: the newest live run, as after `chronav launch` in this directory.
    plain = runner.invoke(app, ["agenda", "list", "--json"], env={"CHRONAV_RUNS": env["CHRONAV_RUNS"],
                                                                 "CHRONAV_ZENOH_CONNECT": None, "CHRONAV_GRAPH": None})
    assert plain.exit_code == 0, plain.output
    assert json.loads(plain.stdout)["graph"] == secured_run.graph

    # The same router and graph, without the run's credentials: refused before anything is sent.
    bare = runner.invoke(app, ["agenda", "cancel", "tv-0908", "--connect", secured_run.endpoint,
                               "--graph", secured_run.graph], env={"CHRONAV_RUNS": env["CHRONAV_RUNS"]})
    assert bare.exit_code == 2
    assert f"something listens at {secured_run.endpoint} but refused a chronav session" in bare.stderr
    assert "requires credentials" in bare.stderr and "--run latest" in bare.stderr
    assert secured_run.world.get_node_by_name("activity/tv-0908").attrs["state"] != "cancelled"


# ---------------------------------------------------------------------------------------------
# watch.
# ---------------------------------------------------------------------------------------------

def test_watcher_lines_offline() -> None:
    graph = DSRGraph("watch_test")
    clock = graph.insert_node(type="clock", name="clock", attrs={"now_s": NOW_S})
    tv = graph.insert_node(type="object", name="tv", attrs={"R": 1.5, "R_band": 0, "active": False})
    out = StringIO()
    watcher = tool.ChangeWatcher(graph, r_step=0.1, as_json=False, out=out)
    watcher.connect()
    activity = graph.insert_node(type="activity", name="activity/tv-0908", attrs={
        "activity_id": "tv-0908", "name": "Game", "object": "tv", "start_s": START_S, "end_s": END_S,
        "state": "upcoming", "participants": []})
    graph.update_node(tv.id, attrs={"R": 1.55})                       # below r_step: no line
    graph.update_node(tv.id, attrs={"R": 3.37, "R_band": 3})
    graph.dispatch()                                                  # lines carry the clock at delivery
    graph.update_node(clock.id, attrs={"now_s": NOW_S + 60})
    graph.update_node(activity.id, attrs={"start_s": START_S + 600, "end_s": END_S + 600})
    graph.update_node(activity.id, attrs={"state": "cancelled"})
    graph.delete_node(activity.id)
    graph.dispatch()
    assert out.getvalue().splitlines() == [
        "09:05:00 activity tv-0908 added: tv 09:08:00-09:40:00 upcoming (Game)",
        "09:05:00 object tv R 1.50 -> 3.37 (dark_orange)",
        "09:06:00 activity tv-0908 moved: 09:08:00-09:40:00 -> 09:18:00-09:50:00",
        "09:06:00 activity tv-0908 upcoming -> cancelled",
        "09:06:00 activity tv-0908 removed from the agenda",
    ]


def test_watch_follows_a_change_live(live: LiveSystem) -> None:
    env = {**os.environ, **live.env, "RERUN": "off"}
    proc = subprocess.Popen([sys.executable, "-m", "tools.cli", "agenda", "watch", "--json", "--count", "3",
                             "--timeout", "30"], cwd=REPO_ROOT, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        assert proc.stderr is not None
        header = proc.stderr.readline()
        assert header.startswith(f"watching the agenda of graph '{live.graph}'"), header + proc.stderr.read()
        assert live.invoke("add", "tv", "09:08", "09:40").exit_code == 0
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, 9)
            proc.wait(10)
    assert proc.returncode == 0, err
    events = [json.loads(line) for line in out.splitlines()]
    by_kind = {e["kind"]: e for e in events}
    assert sorted(by_kind) == ["activity", "object", "request"], events
    assert by_kind["activity"]["event"] == "added" and by_kind["activity"]["activity"]["activity_id"] == "tv-0908"
    assert by_kind["object"]["object"]["R"] == pytest.approx(expected_r())
    assert by_kind["request"]["event"] == "accepted" and "add: tv-0908" in by_kind["request"]["text"]
    assert all(e["time"] == "09:05:00" for e in events)


# ---------------------------------------------------------------------------------------------
# Hostile input to the live agent (issue 12): refused fast, the agent keeps answering.
# ---------------------------------------------------------------------------------------------

HOSTILE = REPO_ROOT / "tests" / "data" / "hostile"


def test_secondly_recurrence_is_refused_and_the_agent_keeps_answering(live: LiveSystem) -> None:
    result = live.invoke("load", str(HOSTILE / "secondly.ics"), "--timeout", "20")
    assert result.exit_code == 1, result.output
    assert "RRULE:FREQ=SECONDLY" in result.stderr and "CHRONAV_LIMIT_RECURRENCE_STEPS" in result.stderr
    assert live.world.nodes_of_type("activity") == []
    after = live.invoke("add", "tv", "09:08", "09:40")
    assert after.exit_code == 0, after.output


def test_participant_not_in_the_scene_is_refused(live: LiveSystem) -> None:
    result = live.invoke("add", "tv", "09:08", "09:40", "--participants", "senior_1, bob")
    assert result.exit_code == 1, result.output
    assert "participant 'bob' is not a person of the scene" in result.stderr
    assert "people: senior_1, therapist" in result.stderr
    assert live.world.nodes_of_type("activity") == []


def test_names_from_the_graph_are_shown_without_terminal_escapes() -> None:
    hostile = "\x1b[2J\x1b]0;pwned\x07[bold]x"
    data = {"graph": "g", "now": "09:05", "activities": [
        {"id": "a", "name": hostile, "object": "tv", "start": "09:08", "end": "09:40", "state": "upcoming",
         "participants": [hostile], "object_R": 1.5}],
        "objects": [{"name": hostile, "R": 1.5, "band": "green", "active": False}]}
    out = StringIO()
    tool.print_snapshot(data, out)
    text = out.getvalue()
    assert "\x1b" not in text and "\x07" not in text
    assert "\\x1b[2J" in text and "[bold]x" in text  # shown, escaped, not interpreted as markup


def test_watch_ends_with_a_line_when_the_system_stops(router: str) -> None:
    """Issue 39: a watch that outlived its system waited silently until Ctrl-C."""
    graph = f"agenda_cli_{os.getpid()}_{next(_graph_numbers)}"
    joined = join("sim_robot", graph=graph, settings=_client(router))
    _populate_world(joined.__enter__())
    stopper = threading.Timer(2.0, lambda: joined.__exit__(None, None, None))
    stopper.start()
    try:
        result = runner.invoke(app, ["agenda", "watch", "--timeout", "30"],
                               env={"CHRONAV_ZENOH_CONNECT": router, "CHRONAV_GRAPH": graph})
    finally:
        stopper.join()
    assert result.exit_code == 0, result.output
    assert f"watch ends: no agent is left in graph '{graph}'" in result.stderr, result.stderr
    assert "(ends with the run, or Ctrl-C)" in result.stderr


def test_watch_says_refused_once() -> None:
    graph = DSRGraph("watch_refused")
    graph.insert_node(type="clock", name="clock", attrs={"now_s": NOW_S})
    out = StringIO()
    watcher = tool.ChangeWatcher(graph, r_step=0.1, as_json=False, out=out)
    watcher.connect()
    request = graph.insert_node(type="agenda_request", name="agenda_request/x", attrs={
        "state": "pending", "requested_by": "staff", "change": "{}"})
    graph.update_node(request.id, attrs={"state": "refused", "message": "refused: no activity with id 'x' today"})
    graph.dispatch()
    assert out.getvalue().splitlines() == ["09:05:00 request from staff refused: no activity with id 'x' today"]

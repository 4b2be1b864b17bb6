"""The simulator's people live the agenda as the DSR holds it: a change staff make with `chronav
agenda` (an agenda_request the agenda agent accepts) moves them at once; what the simulator
writes for the observer and into people.csv."""

from __future__ import annotations

import csv
from pathlib import Path

from agents.agenda.agent import AgendaAgent
from agents.sim_robot.agent import PEOPLE_HEADER, SimRobotAgent
from agents.world.vocabulary import GROUND_TRUTH_PEOPLE
from dsr import DSRGraph
from scenes.clock import parse_clock
from tools.offline_agents import OfflineAgents

SCENE = Path(__file__).resolve().parents[1] / "data" / "crowd_small.yaml"


def agents(tmp_path: Path) -> tuple[DSRGraph, SimRobotAgent, AgendaAgent]:
    centre = OfflineAgents(SCENE, tmp_path, agents=("sim_robot", "agenda"))
    return centre.graph, centre.sim, centre["agenda"]


def truth(graph: DSRGraph) -> dict[str, dict[str, object]]:
    node = graph.get_node_by_name(GROUND_TRUTH_PEOPLE)
    a = node.attrs
    return {name: {"x": x, "y": y, "group": g} for name, x, y, g in zip(a["names"], a["x"], a["y"], a["groups"],
                                                                         strict=True)}


def test_a_cancel_through_the_dsr_sends_the_participants_away_at_once(tmp_path: Path) -> None:
    graph, sim, agenda = agents(tmp_path)
    sim.skip_to(parse_clock("09:45"))
    agenda.step()
    assert truth(graph)["ana"]["group"] == "activity/game"
    graph.insert_node(type="agenda_request", name="agenda_request/cancel-game",
                      attrs={"state": "pending", "change": '{"op": "cancel", "id": "game"}'})
    agenda.step()
    assert graph.get_node_by_name("agenda_request/cancel-game").attrs["state"] == "accepted"
    sim.skip_to(parse_clock("09:45") + 0.5)
    assert truth(graph)["ana"]["group"] == "", "she no longer stands at the cancelled game"
    sim.skip_to(parse_clock("09:46"))
    offline_like = next(p for p in sim.crowd.at(sim.now_s) if p.name == "ana")
    assert offline_like.goal == "", "nor is she walking to it"


def test_people_csv_rows_go_with_the_trajectory_while_driving(tmp_path: Path) -> None:
    graph, sim, _ = agents(tmp_path)
    robot = graph.get_node_by_name("robot")
    graph.update_node(robot.id, attrs={"nav_active": True})
    for _ in range(3):
        graph.update_node(robot.id, attrs={"cmd_vx": 0.2, "cmd_vy": 0.0, "cmd_omega": 0.0,
                                           "cmd_stamp": float(graph.get_node_by_name("robot").attrs["pose_stamp"])})
        sim.clock.rate = 1e9   # no wall-clock pacing in a test
        sim.step()
    sim.teardown()
    with (tmp_path / "trajectory.csv").open() as handle:
        robot_times = [row["t"] for row in csv.DictReader(handle)]
    with (tmp_path / "people.csv").open() as handle:
        reader = csv.DictReader(handle)
        assert tuple(reader.fieldnames or ()) == PEOPLE_HEADER
        rows = list(reader)
    assert robot_times and sorted({row["t"] for row in rows}) == sorted(set(robot_times))
    assert len(rows) == len(robot_times) * len(sim.scene.people)
    assert {row["name"] for row in rows} == {p.name for p in sim.scene.people}


def test_the_robot_waits_for_people_to_clear_the_only_way_then_goes(tmp_path: Path) -> None:
    """Someone stands in the lounge's door, the only way in: the navigation does not fail the
    intention but stops and tries again; once the doorway is clear it plans and drives.  A way that
    stays closed fails after BLOCKED_WAIT_S."""
    from agents.social_navigation.agent import BLOCKED_WAIT_S
    from agents.world.dsr_writers import write_person
    from agents.world.freshness import mark_observed

    centre = OfflineAgents(SCENE, tmp_path, agents=("sim_robot", "social_navigation"))
    graph, sim, nav = centre.graph, centre.sim, centre["social_navigation"]
    write_person(graph, "doorkeeper", "resident", (15.0, 2.4, 0.0), "corridor", sim.now_s)

    def tick(t: float) -> None:
        graph.update_node(graph.get_node_by_name("clock").id, attrs={"now_s": t})
        for agent in ("human_observer", "agenda"):
            mark_observed(graph, agent, t)
        nav.step()

    intention = graph.insert_node(type="intention", name="intention/m/0", attrs={
        "kind": "navigate", "state": "active", "goal_x": 15.0, "goal_y": 6.0, "goal_theta": 1.57,
        "mission_id": "m", "step": 0})
    start = sim.now_s
    tick(start)
    assert nav.intention_id == intention.id and not nav.following and nav.blocked_since == start
    assert graph.get_node_by_name("robot").attrs["nav_active"] is True, "the clock keeps its lockstep pace"
    assert graph.get_node(intention.id).attrs["state"] == "active"
    write_person(graph, "doorkeeper", "resident", (17.0, 6.0, 0.0), "lounge", start + 5.0)
    tick(start + 5.0)
    assert nav.following and nav.blocked_since is None, "the doorway cleared: planned"
    # blocked for good (a closed door): fails after the wait
    write_person(graph, "doorkeeper", "resident", (15.0, 2.4, 0.0), "corridor", start + 6.0)
    second = graph.insert_node(type="intention", name="intention/m/1", attrs={
        "kind": "navigate", "state": "active", "goal_x": 15.0, "goal_y": 6.0, "goal_theta": 1.57,
        "mission_id": "m", "step": 1})
    graph.update_node(intention.id, attrs={"state": "done"})
    tick(start + 6.0)
    assert nav.intention_id == second.id and not nav.following
    tick(start + 6.0 + BLOCKED_WAIT_S + 0.1)
    assert graph.get_node(second.id).attrs["state"] == "failed"
    assert "no path" in graph.get_node(second.id).attrs["reason"]

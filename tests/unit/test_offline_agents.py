"""The offline-agents harness (tools/offline_agents.py) that the agent tests share: what it builds,
in which order it steps, and as whom each agent writes."""

from __future__ import annotations

from pathlib import Path

import pytest

from tools.offline_agents import PERCEIVERS, ROUND_ORDER, WITHOUT_NAVIGATION, OfflineAgents


def test_it_builds_the_named_agents_in_round_order_on_one_graph(tmp_path: Path) -> None:
    centre = OfflineAgents("icra_usecase", tmp_path, agents=("human_observer", "sim_robot"),
                           options={"human_observer": {"seed": "7"}})
    assert list(centre.agents) == ["sim_robot", "human_observer"]
    assert centre["human_observer"].config.options == {"seed": "7"}
    assert centre.graph.get_node_by_name("clock") is not None, "the simulator was set up"
    assert WITHOUT_NAVIGATION == tuple(n for n in ROUND_ORDER if n != "social_navigation")
    assert PERCEIVERS == ("object_recognition", "agenda", "human_observer")
    with pytest.raises(ValueError, match="no such agent"):
        OfflineAgents("icra_usecase", tmp_path, agents=("sim_robot", "navigator"))
    with pytest.raises(ValueError, match="already"):
        centre.add("sim_robot")


def test_a_tick_steps_each_named_agent_as_itself_in_the_given_order(tmp_path: Path,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    centre = OfflineAgents("icra_usecase", tmp_path, agents=("sim_robot", *PERCEIVERS))
    seen: list[tuple[str, str, float]] = []
    for name, agent in centre.agents.items():
        monkeypatch.setattr(agent, "step", lambda name=name, agent=agent: seen.append(
            (name, centre.graph.agent, agent.wall_clock())))
    centre.tick("human_observer", "sim_robot")
    centre.tick()
    period = centre.lockstep.period_s
    assert seen == [("human_observer", "human_observer", 0.0), ("sim_robot", "sim_robot", 0.0),
                    *((name, name, period) for name in ("sim_robot", *PERCEIVERS))]
    assert centre.graph.agent == "offline", "the test writes as itself between ticks"


def test_at_moves_the_clock_and_the_perceivers_see_it_and_a_late_agent_joins(tmp_path: Path) -> None:
    with OfflineAgents("icra_usecase", tmp_path, agents=WITHOUT_NAVIGATION) as centre:
        centre.tick()
        centre.at("09:30")
        assert centre.graph.get_node_by_name("clock").attrs["now_s"] == pytest.approx(9.5 * 3600)
        centre.settle(*PERCEIVERS)
        nav = centre.add("social_navigation")
        assert centre["social_navigation"] is nav and list(centre.agents)[-1] == "social_navigation"
        centre.tick("social_navigation")

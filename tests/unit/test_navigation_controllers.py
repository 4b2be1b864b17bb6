"""The navigation agent drives the controller a run names (-o controller=NAME) and shows it the
world: the path ahead, the tracked people from the DSR and the walls and object footprints as
segments; a controller refused at setup fails the mission instead of crashing the agent."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from agents.lib import registry
from tests.plugin_fixtures import install_fake_plugins
from tools.offline_agents import WITHOUT_NAVIGATION, OfflineAgents


@pytest.fixture
def plugins(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(install_fake_plugins(tmp_path / "site")))
    registry.clear()
    yield
    registry.clear()
    sys.modules.pop("chronav_test_plugins", None)


def _centre_at_1130(tmp_path: Path, controller: str) -> tuple[OfflineAgents, object]:
    centre = OfflineAgents("center_a", tmp_path, agents=WITHOUT_NAVIGATION)
    centre.at("11:30")
    centre.tick("executive")
    return centre, centre.add("social_navigation", controller=controller)


def test_the_chosen_controller_sees_the_path_the_people_and_the_walls(tmp_path, plugins) -> None:
    import chronav_test_plugins  # the installed test package (tests/plugin_fixtures.py)

    centre, nav = _centre_at_1130(tmp_path, "recording_ctrl")
    centre.tick("social_navigation")                 # plans the intention
    centre.tick("sim_robot")
    centre.tick("social_navigation")                 # answers the pose: one control cycle
    assert nav.controller_name == "recording_ctrl" and chronav_test_plugins.SEEN
    seen = chronav_test_plugins.SEEN[-1]
    graph = centre.graph
    people = [n for n in graph.nodes_of_type("person")]
    assert seen.people.shape == (len(people), 5) and len(people) > 0
    assert np.allclose(seen.people[:, 4], nav.maps.params.grid.person_radius_m)
    first = graph.world_pose(people[0].id)
    assert np.any(np.hypot(seen.people[:, 0] - first[0], seen.people[:, 1] - first[1]) < 1e-9)
    assert seen.obstacles.shape[1] == 4 and len(seen.obstacles) >= len(centre.graph.nodes_of_type("object"))
    assert np.allclose(seen.path[-1], nav.goal[:2]) and seen.limits.max_speed_mps == nav.scene.robot.max_speed
    assert graph.get_node_by_name("robot").attrs["cmd_vx"] >= 0.0


def test_a_controller_refused_at_setup_fails_the_mission_not_the_agent(tmp_path, plugins) -> None:
    centre, nav = _centre_at_1130(tmp_path, "no_command")
    assert nav.controller is None
    centre.tick("social_navigation")
    failed = [n for n in centre.graph.nodes_of_type("intention") if n.attrs.get("state") == "failed"]
    assert failed and "controller plug-in 'no_command' from package 'chronav-test-plugins' refused" \
        in failed[0].attrs["reason"]
    assert nav.refusals == 1 and centre.graph.get_node_by_name("robot").attrs["cmd_vx"] == 0.0

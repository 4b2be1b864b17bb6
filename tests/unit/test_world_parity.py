"""One world: what the offline commands see at a time equals what the agents hold at that time.

For every shipped scene and at least five times (the start, just after every scripted door and
agenda event, every mission time), the agents that perceive the world (simulator, object
recognition, human observer without sensor noise, agenda) run on one in-memory DSR up to that sim
time; ``agents.world.offline.graph_at`` builds the graph the offline commands use.  The
executive's symbolic view must be equal node for node and edge for edge (with their attributes),
and the navigation's cost grid cell for cell.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from agents.world.dsr_readers import symbolic_view
from agents.world.navigation import NavigationMaps
from agents.world.offline import graph_at
from agents.world.scene_world import load_world
from scenes.clock import parse_clock
from scenes.loader import SCENES_DIR
from tools.offline_agents import PERCEIVERS, OfflineAgents

# center_week is center_day's building and crowd over seven days (its days' scenes: test_long_run),
# so its 15 s of replay would check center_day's world again
SCENES = sorted(p.stem for p in SCENES_DIR.glob("*.yaml") if p.stem != "center_week")
# A scene whose people live their day (agents/lib/crowd): the offline replay equals the live crowd.
CROWD_SCENE = Path(__file__).resolve().parents[1] / "data" / "crowd_small.yaml"


def scene_path(scene_name: str) -> Path:
    return CROWD_SCENE if scene_name == CROWD_SCENE.stem else SCENES_DIR / f"{scene_name}.yaml"
# The simulator's sensor readings of the moment: not world-model state, not written offline.
SENSOR_ATTRS = {"robot": {"laser_angles", "laser_ranges", "pose_stamp", "v", "vy", "omega"},
                "person": {"seen_s"}}  # when the observer last published a move


def parity_times(scene_name: str) -> list[float]:
    scene = load_world(scene_path(scene_name)).scene
    start, end = scene.clock.start_s, scene.clock.end_s
    times = {start, end - 1.0, (start + end) / 2}
    times |= {parse_clock(c.at) + 1.0 for c in scene.door_changes}
    times |= {parse_clock(c.at) + 1.0 for c in scene.agenda_changes}
    times |= {parse_clock(m.time) for m in scene.missions}
    times = sorted(t for t in times if start <= t < end)
    while len(times) < 5:  # fill the widest gap
        gaps = [(b - a, a, b) for a, b in zip([start, *times], [*times, end], strict=True)]
        _, a, b = max(gaps)
        times = sorted({*times, (a + b) / 2})
    return times


def live_agents(scene_name: str, tmp_path: Path) -> OfflineAgents:
    """The simulator and the perceivers (the observer without sensor noise) on one graph."""
    return OfflineAgents(scene_path(scene_name), tmp_path, agents=("sim_robot", *PERCEIVERS),
                         options={"human_observer": {"noise_xy": "0", "noise_theta": "0"}})


def named(view) -> tuple[dict[str, dict], dict[tuple[str, str, str], dict]]:
    """Nodes by name and edges by (source name, target name, type), attributes without ids."""
    names = {node: data["name"] for node, data in view.nodes(data=True)}
    nodes = {}
    for data in (d for _, d in view.nodes(data=True)):
        skip = SENSOR_ATTRS.get(data["type"], set())
        nodes[data["name"]] = {k: v for k, v in data.items() if k not in skip}
    edges = {(names[a], names[b], key): dict(data) for a, b, key, data in view.edges(keys=True, data=True)}
    return nodes, edges


@pytest.mark.parametrize("scene_name", [*SCENES, CROWD_SCENE.stem])
def test_offline_world_equals_what_the_agents_hold(scene_name: str, tmp_path: Path) -> None:
    world = load_world(scene_path(scene_name))
    nav = NavigationMaps.for_scene(world.scene)
    live = live_agents(scene_name, tmp_path)
    graph = live.graph
    times = parity_times(scene_name)
    assert len(times) >= 5
    for t_s in times:
        live.skip_to(t_s)
        live.settle(*PERCEIVERS)     # live, they run concurrently: until the graph stops changing
        live_nodes, live_edges = named(symbolic_view(graph))
        offline = graph_at(world, t_s)
        off_nodes, off_edges = named(symbolic_view(offline))
        assert live_nodes.keys() == off_nodes.keys(), f"{scene_name} at {t_s}: nodes differ"
        for name, attrs in live_nodes.items():
            assert attrs.keys() == off_nodes[name].keys(), f"{scene_name} at {t_s}: node {name} differs"
            for key, value in attrs.items():
                expected = off_nodes[name][key]
                same = value == pytest.approx(expected) if isinstance(value, float | list) and not \
                    any(isinstance(v, str) for v in (value if isinstance(value, list) else [value])) \
                    else value == expected
                assert same, f"{scene_name} at {t_s}: {name}.{key} is {value!r} live, {expected!r} offline"
        assert live_edges == off_edges, f"{scene_name} at {t_s}: edges differ"
        live_cost, offline_cost = nav.build(graph, t_s).cost, nav.build(offline, t_s).cost
        assert np.array_equal(live_cost, offline_cost), (
            f"{scene_name} at {t_s}: {int(np.sum(live_cost != offline_cost))} cells differ")

"""A seed fixes what the human observer perceives, whatever clock values its loop happens to see.

Regression test: the noise used to be one random stream drawn once per clock value processed, so
two runs with one seed published other poses when one observer saw more clock values than the
other (its loop is not in lockstep with the clock), and `chronav evaluate`'s runs differed.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from agents.world.people import people_at
from agents.world.scene_world import load_world
from scenes.clock import parse_clock
from scenes.loader import SCENES_DIR
from tools.offline_agents import OfflineAgents

SCENE = SCENES_DIR / "icra_usecase.yaml"     # everyone stands still until 10:50


def _seen_at(times: list[float], seed: int, tmp_path: Path) -> dict[str, tuple[float, float, float]]:
    """The people's poses in the DSR after an observer with ``seed`` processed the clock ``times``."""
    tmp_path.mkdir(parents=True)
    centre = OfflineAgents(SCENE, tmp_path, agents=("sim_robot", "human_observer"),
                           options={"human_observer": {"seed": str(seed)}})
    for t in times:
        centre.skip_to(t)
        centre.tick("human_observer")
    graph = centre.graph
    return {node.name: graph.world_pose(node.id) for node in graph.nodes_of_type("person")}


def test_one_seed_one_world_whatever_clock_values_were_seen(tmp_path: Path) -> None:
    t0 = parse_clock("09:30")
    few = _seen_at([t0, t0 + 5.0], seed=3, tmp_path=tmp_path / "a")
    many = _seen_at([t0 + 0.1 * k for k in range(51)], seed=3, tmp_path=tmp_path / "b")
    assert few == many
    other = _seen_at([t0, t0 + 5.0], seed=4, tmp_path=tmp_path / "c")
    truth = {p.name: (p.x, p.y) for p in people_at(load_world(SCENE), t0)}
    for name, (x, y, _) in few.items():
        assert (x, y) != pytest.approx(other[name][:2], abs=1e-9), "another seed, another detection"
        assert (x, y) == pytest.approx(truth[name], abs=0.1) and (x, y) != truth[name]   # noisy, near the truth

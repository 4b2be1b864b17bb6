"""Benchmark of the symbolic (grammar) planner on generated care centres.

Prints ONE flat JSON object: ``plan_ms_rooms_N`` (median wall time of ``plan_mission`` for a
``room:`` mission, building the world index included) for N = 10, 50, 200 rooms, with the plan
length and the number of expanded states for context; ``plan_ms_object_rooms_N`` for an
``object:`` mission to the same room (more rules relevant, more states); and the time to parse
the shipped grammar. ``plan_cpu_ms_*`` are the same medians in process CPU time (steadier than
wall time on a shared machine). Goals: <= 100 ms at 50 rooms, < 200 ms for the object mission at
200 rooms.

A centre is a grid of rooms (doors between horizontal and vertical neighbours, a few closed),
two objects and two people per room, and running group activities in ~10% of the rooms, which
the agenda rules forbid entering: the robot, in the first room, is sent to the room farthest
from it, so plans must detour around busy rooms.

Run: ``.venv/bin/python tools/bench/bench_planner_symbolic.py [--repeat 7]``
"""

from __future__ import annotations

import argparse
import json
import math
import random
import statistics
import sys
import time
from collections import deque
from pathlib import Path

import networkx as nx

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from agents.world.vocabulary import ActivityState
from grammar.missions import plan_mission
from grammar.parser import default_grammar_path, load_grammar

SIZES = (10, 50, 200)


def generate_centre(rooms: int, seed: int = 7) -> tuple[nx.MultiDiGraph, str]:
    """A symbolic centre with ``rooms`` rooms; returns the graph and the farthest room's name."""
    rng = random.Random(seed)
    cols = max(2, math.ceil(math.sqrt(rooms)))
    graph = nx.MultiDiGraph()

    def node(name: str, node_type: str, **attrs: object) -> None:
        graph.add_node(name, type=node_type, name=name, **attrs)

    def edge(src: str, dst: str, label: str, **attrs: object) -> None:
        graph.add_edge(src, dst, key=label, type=label, **attrs)

    names = [f"room{i}" for i in range(rooms)]
    for name in names:
        node(name, "room")
    adjacency: dict[str, list[str]] = {n: [] for n in names}
    for i in range(rooms):
        r, c = divmod(i, cols)
        for j in ((i + 1) if c + 1 < cols else None, i + cols):
            if j is None or j >= rooms:
                continue
            door = f"door{i}_{j}"
            closed = rng.random() < 0.05
            node(door, "door", open=not closed)
            edge(names[i], names[j], "connected", door=door)
            if not closed:
                adjacency[names[i]].append(names[j])
                adjacency[names[j]].append(names[i])
    node("robot", "omnirobot")
    edge("robot", names[0], "in")
    busy: set[str] = set()
    for i, room in enumerate(names):
        for k in range(2):
            node(f"obj{i}_{k}", "object")
            edge(f"obj{i}_{k}", room, "in")
            node(f"person{i}_{k}", "person", role="resident")
            edge(f"person{i}_{k}", room, "in")
        if rng.random() < 0.5:
            edge(f"person{i}_0", f"person{i}_1", "interacting")
        if i > 0 and rng.random() < 0.1:
            busy.add(room)
            node(f"therapy{i}", "activity", state=ActivityState.RUNNING)
            edge(f"therapy{i}", f"obj{i}_0", "has")
            edge(f"person{i}_0", f"therapy{i}", "participant")
            edge(f"person{i}_1", f"therapy{i}", "participant")
    # farthest reachable room from the start, through open doors and free rooms
    distance = {names[0]: 0}
    queue = deque([names[0]])
    while queue:
        room = queue.popleft()
        for other in adjacency[room]:
            if other not in distance and other not in busy:
                distance[other] = distance[room] + 1
                queue.append(other)
    farthest = max(distance, key=lambda n: (distance[n], n))
    return graph, farthest


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    result: dict[str, float | int] = {}
    t0 = time.perf_counter()
    grammar = load_grammar(default_grammar_path())
    result["parse_ms_social_navigation"] = round((time.perf_counter() - t0) * 1000, 2)
    for rooms in SIZES:
        graph, goal = generate_centre(rooms)
        for kind, mission in (("", f"room:{goal}"), ("object_", f"object:obj{goal[4:]}_1")):
            times, cpu = [], []
            outcome = None
            for _ in range(args.repeat):
                t0, c0 = time.perf_counter(), time.process_time()
                outcome = plan_mission(grammar, graph, mission)
                times.append((time.perf_counter() - t0) * 1000)
                cpu.append((time.process_time() - c0) * 1000)
            assert outcome is not None
            if not outcome.found:
                raise SystemExit(f"no plan for {mission} at {rooms} rooms: {outcome.reason}")  # type: ignore[union-attr]
            result[f"plan_ms_{kind}rooms_{rooms}"] = round(statistics.median(times), 2)
            result[f"plan_cpu_ms_{kind}rooms_{rooms}"] = round(statistics.median(cpu), 2)
            result[f"plan_steps_{kind}rooms_{rooms}"] = len(outcome.steps)  # type: ignore[union-attr]
            result[f"expanded_states_{kind}rooms_{rooms}"] = outcome.expanded
    print(json.dumps(result))


if __name__ == "__main__":
    main()

"""The field's standard crowd scenarios as chronav scenes: circle crossing, corridor counterflow,
perpendicular crossing, a doorway bottleneck (scenes/crowds/, docs/crowds.md).

Why generated, and why as recordings: each scenario is a handful of people who walk from a start to
a goal (CrowdNav's humans are ORCA agents heading for their goals); chronav replays such people
with ``routine: replay`` and ``crowd.replay: reactive`` (agents/lib/crowd/replay.py: they head along
their straight walk to its end, avoiding the robot and each other with ORCA).  This script writes,
for each scenario, the planned walks as an ETH/UCY text file (``frame id x y``, 0.4 s a frame) and
the scene that replays them, from a seed, so the shipped files are reproducible from this file
alone (``tests/unit/test_standard_scenarios.py`` regenerates them and compares).

Run: ``.venv/bin/python tools/standard_scenarios.py [--out scenes/crowds]``
"""

from __future__ import annotations

import argparse
import math
import textwrap
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
FRAME_DT_S = 0.4
HUMAN_RADIUS_M = 0.3          # CrowdNav's human radius
DISCOMFORT_M = 0.2            # CrowdNav's discomfort distance (starts drawn this far apart at least)


@dataclass(frozen=True)
class Walk:
    """One person's planned walk: a polyline at a speed, starting at ``t0`` s after the recording's start."""

    points: tuple[tuple[float, float], ...]
    speed_mps: float
    t0: float


@dataclass(frozen=True)
class Scenario:
    name: str
    source: str                               # where the definition comes from (comment and docs)
    description: str
    walls: list[list[tuple[float, float]]]
    rooms: list[tuple[str, list[tuple[float, float]]]]
    doors: list[tuple[str, tuple[str, str], tuple[float, float], float]]
    robot: tuple[float, float, float]
    goal: tuple[float, float, float]
    walks: list[Walk]
    seed: int


def _box(x0: float, y0: float, x1: float, y1: float) -> list[tuple[float, float]]:
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


def circle_crossing(seed: int) -> Scenario:
    """CrowdNav's circle crossing (Chen et al. 2019): humans on a circle of radius 4 m, each walking to
    the point opposite; start angles drawn at random, starts perturbed by up to half a metre (times
    their preferred speed), redrawn when closer than two bodies plus the discomfort distance to
    another human or to the robot's start or goal; the robot crosses from (0, -4) to (0, 4)."""
    rng = np.random.default_rng(seed)
    robot, goal = (0.0, -4.0), (0.0, 4.0)
    starts: list[tuple[float, float]] = []
    while len(starts) < 5:
        angle = rng.random() * 2 * math.pi
        noise = (rng.random(2) - 0.5) * 1.0
        p = (4.0 * math.cos(angle) + noise[0], 4.0 * math.sin(angle) + noise[1])
        others = [*starts, *[(-x, -y) for x, y in starts], robot, goal]
        if all(math.dist(p, q) >= 2 * HUMAN_RADIUS_M + DISCOMFORT_M for q in others) \
                and all(math.dist((-p[0], -p[1]), q) >= 2 * HUMAN_RADIUS_M + DISCOMFORT_M for q in others):
            starts.append(p)
    walks = [Walk(((x, y), (-x, -y)), 1.0, 0.0) for x, y in starts]
    return Scenario("circle_crossing", "CrowdNav (Chen, Liu, Kreiss, Alahi, ICRA 2019, 'Crowd-Robot Interaction'): "
                    "5 humans on a 4 m circle walk to the opposite point at 1 m/s (ORCA), the robot crosses "
                    "from (0, -4) to (0, 4)",
                    "Circle crossing: five people on a 4 m circle each walk to the opposite point; the robot "
                    "crosses the circle through its centre.",
                    [[*_box(-7, -7, 7, 7), (-7, -7)]], [("square", _box(-7, -7, 7, 7))], [],
                    (*robot, math.pi / 2), (*goal, math.pi / 2), walks, seed)


def corridor_counterflow(seed: int) -> Scenario:
    """Two opposite flows in a 3 m corridor (the bidirectional corridor in which Helbing and Molnár's
    social force model forms lanes, 1995; Francis et al. 2023 list 'narrow hallway' and 'frontal
    approach' among the scenarios to test): three people walk east, three west, staggered; the robot
    drives east with the first flow."""
    rng = np.random.default_rng(seed)
    walks = []
    for k in range(3):
        y = float(rng.uniform(0.7, 2.3))
        walks.append(Walk(((1.0, y), (15.0, y)), float(rng.uniform(0.9, 1.2)), 6.0 + 4.0 * k))
    for k in range(3):
        y = float(rng.uniform(0.7, 2.3))
        walks.append(Walk(((15.0, y), (1.0, y)), float(rng.uniform(0.9, 1.2)), 3.0 * k))
    return Scenario("corridor_counterflow", "bidirectional corridor flow (Helbing and Molnár 1995, 'Social force "
                    "model for pedestrian dynamics': lanes form); 'narrow hallway' / 'frontal approach' in Francis "
                    "et al. 2023, 'Principles and Guidelines for Evaluating Social Robot Navigation Algorithms'",
                    "Corridor counterflow: in a 16 m x 3 m corridor three people walk east and three west; the "
                    "robot drives east, meeting the westbound ones head on.",
                    [[(0, 0), (16, 0)], [(0, 3), (16, 3)], [(0, 0), (0, 3)], [(16, 0), (16, 3)]],
                    [("corridor", _box(0, 0, 16, 3))], [], (0.8, 1.5, 0.0), (15.2, 1.5, 0.0), walks, seed)


def perpendicular_crossing(seed: int) -> Scenario:
    """A stream of people crossing the robot's way at a right angle ('crossing' in Francis et al.
    2023 and in Gao and Huang's 2022 survey of socially-aware navigation evaluation): six people walk
    north across the middle of a 14 m square, two seconds apart, while the robot drives east."""
    rng = np.random.default_rng(seed)
    walks = [Walk(((x, -6.0), (x, 6.0)), float(rng.uniform(0.9, 1.3)), 4.0 + 2.0 * k + float(rng.uniform(-0.5, 0.5)))
             for k, x in enumerate(rng.uniform(-1.5, 1.5, 6).tolist())]
    return Scenario("perpendicular_crossing", "'crossing' (perpendicular traffic) in Francis et al. 2023 and in "
                    "Gao and Huang 2022, 'Evaluation of Socially-Aware Robot Navigation'",
                    "Perpendicular crossing: six people cross the square northward, two seconds apart, through "
                    "the middle of the robot's eastward way.",
                    [[*_box(-7, -7, 7, 7), (-7, -7)]], [("square", _box(-7, -7, 7, 7))], [],
                    (-6.0, 0.0, 0.0), (6.0, 0.0, 0.0), walks, seed)


def doorway_bottleneck(seed: int) -> Scenario:
    """A 1.2 m doorway between two rooms (the bottleneck of pedestrian dynamics, Helbing et al. 2000,
    Seyfried et al. 2009; 'narrow doorway' in Francis et al. 2023): five people in the east room go
    through the door to the west room, staggered, while the robot goes the other way through it."""
    rng = np.random.default_rng(seed)
    walks = []
    for k in range(5):
        start = (float(rng.uniform(8.0, 11.0)), float(rng.uniform(1.0, 5.0)))
        goal = (float(rng.uniform(1.0, 4.0)), float(rng.uniform(1.0, 5.0)))
        walks.append(Walk((start, (6.6, 3.0), (5.4, 3.0), goal), float(rng.uniform(0.9, 1.2)), 1.5 * k))
    walls: list[list[tuple[float, float]]] = [[(0, 0), (12, 0), (12, 6), (0, 6), (0, 0)], [(6, 0), (6, 2.4)], [(6, 3.6), (6, 6)]]
    return Scenario("doorway_bottleneck", "the bottleneck of pedestrian dynamics (Helbing, Farkas, Vicsek 2000; "
                    "Seyfried et al. 2009); 'narrow doorway' in Francis et al. 2023",
                    "Doorway bottleneck: five people in the east room walk through a 1.2 m door to the west room "
                    "while the robot goes through it the other way.",
                    walls, [("west", _box(0, 0, 6, 6)), ("east", _box(6, 0, 12, 6))],
                    [("door", ("west", "east"), (6.0, 3.0), 1.2)], (2.0, 3.0, 0.0), (10.0, 3.0, 0.0), walks, seed)


SCENARIOS: dict[str, Callable[[int], Scenario]] = {
    "circle_crossing": circle_crossing, "corridor_counterflow": corridor_counterflow,
    "perpendicular_crossing": perpendicular_crossing, "doorway_bottleneck": doorway_bottleneck}


def recording_text(walks: list[Walk]) -> str:
    """The walks as an ETH/UCY file: each person every 0.4 s from their start to their goal."""
    lines: dict[int, list[str]] = {}
    for pid, walk in enumerate(walks, start=1):
        pts = np.array(walk.points, dtype=float)
        legs = np.hypot(*np.diff(pts, axis=0).T)
        along = np.concatenate([[0.0], np.cumsum(legs)])
        first = int(math.ceil(walk.t0 / FRAME_DT_S - 1e-9))
        last = int(math.ceil((walk.t0 + along[-1] / walk.speed_mps) / FRAME_DT_S))
        for k in range(first, last + 1):
            s = min((k * FRAME_DT_S - walk.t0) * walk.speed_mps, along[-1])
            x, y = np.interp(s, along, pts[:, 0]), np.interp(s, along, pts[:, 1])
            lines.setdefault(k, []).append(f"{10 * k}\t{pid}\t{x:.4f}\t{y:.4f}")
    return "".join(line + "\n" for k in sorted(lines) for line in lines[k])


def _flow(values: object) -> str:
    if isinstance(values, (list, tuple)):
        return "[" + ", ".join(_flow(v) for v in values) + "]"
    if isinstance(values, float):
        return f"{round(values, 3):g}"
    return str(values)


def scene_text(s: Scenario) -> str:
    doors = "".join(f"  - {{name: {n}, between: {_flow(list(b))}, position: {_flow(list(p))}, width: {w:g}}}\n"
                    for n, b, p, w in s.doors)
    people = "".join(f"  - {{name: p{pid}, role: visitor, routine: replay, track: {pid}, "
                     f"pose: {_flow([w.points[0][0], w.points[0][1], math.atan2(w.points[1][1] - w.points[0][1], w.points[1][0] - w.points[0][0])])}}}\n"
                     for pid, w in enumerate(s.walks, start=1))
    about = "".join(f"# {line}\n" for line in textwrap.wrap(s.description, 100))
    about += "".join(f"# {line}\n" for line in textwrap.wrap(f"Where the definition comes from: {s.source}.", 100))
    return f"""{about}# The people's planned walks (start, goal, speed, start time; seeded, seed {s.seed}) are {s.name}.txt,
# replayed reactively: each heads along their walk to its end and avoids the robot and the others
# with ORCA (docs/crowds.md). Written by tools/standard_scenarios.py; regenerate, do not edit.
name: {s.name}
description: "{s.description}"
clock: {{start: "09:00", end: "09:03", rate: 60, skip_idle: true}}
crowd: {{seed: {s.seed}, replay: reactive}}
recordings:
  - {{name: walks, file: {s.name}.txt, dt: {FRAME_DT_S:g}, start: "09:00:02"}}
walls:
{"".join(f"  - {_flow([list(p) for p in w])}" + chr(10) for w in s.walls)}rooms:
{"".join(f"  - {{name: {n}, polygon: {_flow([list(p) for p in poly])}}}" + chr(10) for n, poly in s.rooms)}doors:
{doors or "  []" + chr(10)}robot: {{pose: {_flow(list(s.robot))}}}
missions:
  - {{id: cross, time: "09:00:02", goal: {{pose: {_flow(list(s.goal))}}}, description: "the robot's crossing"}}
people:
{people}"""


def write_all(out: Path, seed: int = 0) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, build in SCENARIOS.items():
        scenario = build(seed)
        (out / f"{name}.txt").write_text(recording_text(scenario.walks), encoding="utf-8")
        (out / f"{name}.yaml").write_text(scene_text(scenario), encoding="utf-8")
        written.append(out / f"{name}.yaml")
    return written


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "scenes" / "crowds")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    for path in write_all(args.out, args.seed):
        print(path)


if __name__ == "__main__":
    main()

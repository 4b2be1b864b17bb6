"""`chronav metrics --definitions hunav` against an independent transcription of HuNavSim's evaluator.

The transcription below follows robotics-upo/hunav_sim ``hunav_evaluator/hunav_evaluator/
hunav_metrics.py`` and ``sfm.py`` (ROS 2 humble; the version whose time_not_moving tests
``abs(angular_vel < 0.02)``) line by line on plain Python lists of per-sample records, the way their
code walks its ``agents`` and ``robot`` message lists: no chronav metric code is used.  It runs on a
recorded chronav run (tests/data/recorded_mission: center_day's m_group mission, 159 robot samples,
the ten people nearest to the robot, people.csv written at the robot's sample times), so every
sample is one of HuNavSim's (robot, agents) pairs without interpolation.

What chronav supplies as HuNavSim's inputs: the robot's ``linear_vel`` / ``angular_vel`` and velocity
vector are forward differences of its samples (the last repeats the one before), a person's
``linear_vel`` is |(vx, vy)|, group ids are the ``group`` column ("" = -1), and an agent's
``closest_obs`` is the nearest point of the scene's walls and footprints (the robot's is empty, as
in HuNavSim's Gazebo pipeline).
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import pytest
import shapely
import shapely.ops
from typer.testing import CliRunner

from tools.cli import app

RUN = Path(__file__).resolve().parents[1] / "data" / "recorded_mission"
R = 0.35          # HuNavSim's default radii (robot and agents)
GOAL = (21.0, 8.0)
GOAL_RADIUS = 0.1


# --- the transcription ------------------------------------------------------------------------

def norm_angle(a: float) -> float:                       # hunav_metrics.normalize_angle
    while a <= -math.pi:
        a += 2 * math.pi
    while a > math.pi:
        a -= 2 * math.pi
    return a


def sfm_norm_angle(a: float) -> float:                   # sfm.SFM.normalize_angle (one step)
    if a > math.pi:
        a -= 2 * math.pi
    elif a < -math.pi:
        a += 2 * math.pi
    return a


def load(run: Path = RUN) -> tuple[list[dict], list[list[dict]]]:
    """HuNavSim's robot list and agents list (one entry per sample: the people with a row at the
    robot sample's time, none when nobody was there)."""
    traj = [[float(v) for v in row] for row in list(csv.reader((run / "trajectory.csv").open()))[1:]]
    by_time: dict[str, list[dict]] = {}
    for t, name, _role, x, y, th, vx, vy, group in list(csv.reader((run / "people.csv").open()))[1:]:
        by_time.setdefault(t, []).append({"id": name, "x": float(x), "y": float(y), "yaw": float(th),
                                          "vx": float(vx), "vy": float(vy), "radius": R,
                                          "linear_vel": math.hypot(float(vx), float(vy)),
                                          "group_id": group if group else -1})
    times = [f"{row[0]:.3f}" for row in traj]
    assert set(by_time) <= set(times), "people.csv is written at the robot's sample times"
    robot = []
    for i, (t, x, y, th) in enumerate(traj):
        j = i if i + 1 < len(traj) else i - 1
        dt = traj[j + 1][0] - traj[j][0]
        vx, vy = (traj[j + 1][1] - traj[j][1]) / dt, (traj[j + 1][2] - traj[j][2]) / dt
        w = math.remainder(traj[j + 1][3] - traj[j][3], 2 * math.pi) / dt
        robot.append({"id": "robot", "t": t, "x": x, "y": y, "yaw": th, "vx": vx, "vy": vy, "radius": R,
                      "linear_vel": math.hypot(vx, vy), "angular_vel": w, "closest_obs": []})
    return robot, [by_time.get(t, []) for t in times]


def dist(a: dict, b: dict) -> float:
    return math.sqrt((a["x"] - b["x"]) ** 2 + (a["y"] - b["y"]) ** 2)


def force_two(a1: dict, a2: dict) -> tuple[float, float]:
    """sfm.computeSocialForceTwoAgents: the force a1 provokes in a2 (with its swapped atan2)."""
    dx, dy = a1["x"] - a2["x"], a1["y"] - a2["y"]
    d = math.sqrt(dx * dx + dy * dy)
    ddx, ddy = dx / d, dy / d
    ix = 2.0 * (a2["vx"] - a1["vx"]) + ddx
    iy = 2.0 * (a2["vy"] - a1["vy"]) + ddy
    il = math.sqrt(ix * ix + iy * iy)
    idx, idy = ix / il, iy / il
    theta = sfm_norm_angle(math.atan2(ddy, ddx) - math.atan2(idx, idy))
    b = 0.35 * il
    fv = -math.exp(-d / b - (3.0 * b * theta) ** 2)
    sign = (theta > 0) - (theta < 0)
    fa = -sign * math.exp(-d / b - (2.0 * b * theta) ** 2)
    return 2.1 * (fv * idx + fa * -idy), 2.1 * (fv * idy + fa * idx)


def obstacle_force(agent: dict, points: list[tuple[float, float]]) -> float:
    """|sfm.computeObstacleForce| (0 when the agent's closest_obs list is empty)."""
    if not points:
        return 0.0
    fx = fy = 0.0
    for ox, oy in points:
        d = math.hypot(agent["x"] - ox, agent["y"] - oy)
        mag = 10.0 * math.exp(-(d - agent["radius"]) / 0.2)
        fx += mag * (agent["x"] - ox) / d
        fy += mag * (agent["y"] - oy) / d
    return math.hypot(fx / len(points), fy / len(points))


def band(d: float, k: str) -> int:
    return int({"intimate": d < 0.45, "personal": 0.45 <= d < 1.2, "social": 1.2 <= d < 3.6}[k])


def transcription(robot: list[dict], agents: list[list[dict]], obstacles: shapely.Geometry) -> dict[str, float]:
    n = len(robot)
    out: dict[str, float] = {}
    out["time_to_reach_goal"] = robot[-1]["t"] - robot[0]["t"]
    out["path_length"] = sum(dist(robot[i + 1], robot[i]) for i in range(n - 1))
    out["cumulative_heading_changes"] = sum(abs(norm_angle(robot[i]["yaw"] - robot[i + 1]["yaw"]))
                                            for i in range(n - 1))
    total, closest, everyone = 0.0, [], []
    for r, ags in zip(robot, agents, strict=True):
        m = 10000.0
        for a in ags:
            d = dist(r, a) - r["radius"] - a["radius"]
            if d < m:
                m = max(d, 0.0)
            everyone.append(max(d, 0.0))
        closest.append(m)
        if ags:                                  # if(len(agents[i].agents)>0)
            total += m
    out["avg_distance_to_closest_person"] = total / n
    out["minimum_distance_to_people"] = min(everyone)
    out["maximum_distance_to_people"] = max(dist(r, a) - r["radius"] for r, ags in zip(robot, agents) for a in ags)
    for k in ("intimate", "personal", "social"):
        out[f"{k}_space_intrusions"] = 100.0 * sum(band(m, k) for m in closest) / n
    ids = []
    for a in agents[0]:
        if a["group_id"] != -1 and a["group_id"] not in ids:
            ids.append(a["group_id"])
    for k in ("intimate", "personal", "social"):
        count = 0
        for r, ags in zip(robot, agents, strict=True):
            m = 10000.0
            for gid in ids:
                members = [a for a in ags if a["group_id"] == gid]
                if not members:          # HuNavSim divides by zero here; chronav skips the group
                    continue
                cx = sum(a["x"] + 1.5 * math.cos(a["yaw"]) for a in members) / len(members)
                cy = sum(a["y"] + 1.5 * math.sin(a["yaw"]) for a in members) / len(members)
                m = min(m, math.hypot(r["x"] - cx, r["y"] - cy) - r["radius"])
            count += band(m, k)
        out[f"group_{k}_space_intrusions"] = 100.0 * count / n if ids else 0.0
    robot_c = person_c = 0
    for r, ags in zip(robot, agents, strict=True):
        for a in ags:
            if dist(r, a) - r["radius"] - a["radius"] < 0.02:
                nrx = (r["x"] - a["x"]) * math.cos(a["yaw"]) + (r["y"] - a["y"]) * math.sin(a["yaw"])
                nry = -(r["x"] - a["x"]) * math.sin(a["yaw"]) + (r["y"] - a["y"]) * math.cos(a["yaw"])
                alpha = math.atan2(nry, nrx)
                nrx = (a["x"] - r["x"]) * math.cos(r["yaw"]) + (a["y"] - r["y"]) * math.sin(r["yaw"])
                nry = -(a["x"] - r["x"]) * math.sin(r["yaw"]) + (a["y"] - r["y"]) * math.cos(r["yaw"])
                alpha2 = math.atan2(nrx, nry)
                if abs(alpha) < abs(alpha2) and r["linear_vel"] > a["linear_vel"]:
                    robot_c += 1
                elif abs(alpha) > abs(alpha2) and r["linear_vel"] < a["linear_vel"]:
                    person_c += 1
                elif abs(alpha) < abs(alpha2) and r["linear_vel"] < a["linear_vel"]:
                    robot_c += 1
                elif abs(alpha) > abs(alpha2) and r["linear_vel"] > a["linear_vel"]:
                    person_c += 1
                elif abs(alpha) == abs(alpha2) and r["linear_vel"] == a["linear_vel"]:
                    robot_c += 1
                    person_c += 1
    out["robot_on_person_collision"], out["person_on_robot_collision"] = robot_c, person_c
    step = out["time_to_reach_goal"] / n
    out["time_not_moving"] = step * sum(1 for r in robot if r["linear_vel"] < 0.01 and abs(r["angular_vel"] < 0.02))
    goal = {"x": GOAL[0], "y": GOAL[1]}
    out["completed"] = dist(robot[-1], goal) - GOAL_RADIUS < 0.05
    out["minimum_distance_to_target"] = min(dist(r, goal) for r in robot)
    out["final_distance_to_target"] = dist(robot[-1], goal)
    out["avg_robot_linear_speed"] = sum(r["linear_vel"] for r in robot) / n
    out["avg_robot_angular_speed"] = sum(abs(r["angular_vel"]) for r in robot) / n
    acc = jerk = 0.0
    for i in range(n - 1):
        dv = robot[i + 1]["linear_vel"] - robot[i]["linear_vel"]
        dt = robot[i + 1]["t"] - robot[i]["t"]
        if dt != 0.0:
            acc += dv / dt
            jerk += dv / dt / dt
    out["avg_acceleration"], out["avg_overacceleration"] = acc / n, jerk / n
    out["avg_pedestrian_velocity"] = sum(a["linear_vel"] for ags in agents for a in ags) / (n * len(agents[0]))
    out["avg_closest_pedestrian_velocity"] = sum(      # nobody there: closest = Agent(), linear_vel 0
        min(ags, key=lambda a, r=r: dist(r, a))["linear_vel"] if ags else 0.0 for r, ags in zip(robot, agents)) / n
    on_agents = on_robot = work = 0.0
    for r, ags in zip(robot, agents, strict=True):
        sx = sy = 0.0
        for a in ags:
            fx, fy = force_two(a, r)
            on_robot += math.hypot(fx, fy)
            sx, sy = sx + fx, sy + fy
            gx, gy = force_two(r, a)
            on_agents += math.hypot(gx, gy)
            work += math.hypot(gx, gy)
        work += math.hypot(sx, sy) + obstacle_force(r, r["closest_obs"])
    out["social_force_on_agents"], out["social_force_on_robot"], out["social_work"] = on_agents, on_robot, work
    out["obstacle_force_on_robot"] = sum(obstacle_force(r, r["closest_obs"]) for r in robot)
    total = 0.0
    for ags in agents:
        s = 0.0
        for a in ags:
            near = shapely.ops.nearest_points(obstacles, shapely.Point(a["x"], a["y"]))[0]
            s += obstacle_force(a, [(near.x, near.y)])
        if ags:                                  # HuNavSim divides by zero here; chronav skips the sample
            total += s / len(ags)
    out["obstacle_force_on_agents"] = total
    return out


# --- the test ---------------------------------------------------------------------------------

def test_hunav_definitions_match_a_transcription_of_hunav_metrics_on_a_recorded_run() -> None:
    from agents.world.offline import scene_obstacles
    from agents.world.scene_world import load_world

    result = CliRunner().invoke(app, ["metrics", "center_day", str(RUN / "trajectory.csv"), "--definitions", "hunav",
                                      "--goal", f"{GOAL[0]},{GOAL[1]}", "--json"])
    assert result.exit_code == 0, result.output
    ours = json.loads(result.stdout)
    assert ours["definitions"] == "hunav" and ours["robot_radius_m"] == R and ours["person_radius_m"] == R
    robot, agents = load()
    theirs = transcription(robot, agents, scene_obstacles(load_world("center_day").scene))
    assert set(ours["metrics"]) == set(theirs), "the JSON keys are HuNavSim's metric names"
    for key, value in theirs.items():
        assert ours["metrics"][key] == pytest.approx(value, rel=1e-6, abs=1e-6), key
    # the run is informative: someone close, contacts counted per sample, forces at work
    assert theirs["minimum_distance_to_people"] < 0.45 and theirs["robot_on_person_collision"] \
        + theirs["person_on_robot_collision"] > 0
    assert theirs["social_work"] > 0 and theirs["obstacle_force_on_agents"] > 0

    # the published definitions on the same run: the same path, time and heading changes; a contact is
    # one collision however many samples it lasts (none here: the bodies never touch); without --goal the target metrics say why
    published = CliRunner().invoke(app, ["metrics", "center_day", str(RUN / "trajectory.csv"), "--json"])
    assert published.exit_code == 0, published.output
    p = json.loads(published.stdout)["metrics"]
    assert p["distance_travelled_m"] == pytest.approx(theirs["path_length"])
    assert p["duration_s"] == pytest.approx(theirs["time_to_reach_goal"])
    assert p["cumulative_heading_change_rad"] == pytest.approx(theirs["cumulative_heading_changes"])
    assert p["dynamic"]["min_distance_to_people_m"] > theirs["minimum_distance_to_people"] == 0.0, \
        "the scene's 0.25 m radii, not HuNavSim's 0.35 m"
    assert p["dynamic"]["robot_on_person_collisions"] + p["dynamic"]["person_on_robot_collisions"] \
        < theirs["robot_on_person_collision"] + theirs["person_on_robot_collision"]
    assert p["dynamic"]["completed"] is None and "no target" in p["dynamic"]["missing"]["completed"]


def test_metrics_help_gives_the_people_header_the_reader_wants() -> None:
    from agents.lib.metrics.metrics import PEOPLE_HEADER

    result = CliRunner().invoke(app, ["metrics", "--help"], env={"COLUMNS": "400"})
    assert ",".join(PEOPLE_HEADER) in " ".join(result.output.split())

"""`chronav export RUN --format mcap --out FILE.mcap`: a finished run as a rosbag2 MCAP file.

Why rosbag2 MCAP (through rosbags' writer): it is what ``ros2 bag play``, Foxglove and rosbags
read, and every channel carries its ROS 2 type with its message definition and RIHS01 hash.
The same message builders and grids as the live bridge (agents/ros_bridge) make the messages, so
a bag and a live session show the same thing; log and header times are the scene's clock (its
date and timezone, plus the sim seconds of the day).

What a run keeps, and so what the bag has (docs/ros2.md says it too):
- ``/odom``, ``/tf`` (map -> odom -> base_link, map -> person/<name>) and ``/clock`` at every
  sample of ``trajectory.csv`` (the robot's pose while it drives; velocities by differences);
- ``/people`` at every time of ``people.csv`` (positions and velocities of everyone);
- ``/map`` once (TRANSIENT_LOCAL, as the bridge offers it) and, at the start of every drive,
  ``/social_costmap``, ``/keepout_filter_mask`` and ``/agenda`` of the world at that time as the
  offline commands rebuild it (agents/world/offline.py: the scripted world, people replayed
  from the day's start, so the same as live until the robot has influenced someone).
- ``/plan`` at every path the navigation adopted (``plans.jsonl``, agents/world/plans_file.py),
  stamped with the sim time it was adopted, as the live bridge publishes it.
The laser is not written to the run's files, so ``/scan`` is not in the bag.
"""

from __future__ import annotations

import json
import math
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from agents.lib.metrics.metrics import MetricsInputError, read_people_csv, read_trajectory_csv
from agents.ros_bridge import messages as msgs
from agents.ros_bridge.config import Frames, Topics
from agents.ros_bridge.maps import RosMaps
from agents.ros_bridge.types import serialize, typestore
from agents.world.offline import graph_at
from agents.world.plans_file import PLANS_FILE, read_plans
from agents.world.scene_world import load_world
from agents.world.vocabulary import activities
from scenes.angles import wrap_angle

#: a gap longer than this between trajectory samples starts a new drive (the simulator writes
#: samples every 0.1 s of sim time while the robot drives)
NEW_DRIVE_GAP_S = 1.0
TOPICS = Topics()


class ExportError(Exception):
    """The run cannot be exported (missing, unfinished, unreadable files)."""


def find_run(run: str, runs_dir: Path) -> Path:
    """``latest`` (the newest finished run), a run directory, or a run id under the runs directory."""
    if run == "latest":
        from tools.system.runs import RunError, latest_finished_run

        try:
            return latest_finished_run(runs_dir)
        except RunError as exc:
            raise ExportError(str(exc)) from None
    for candidate in (Path(run), runs_dir / run):
        if candidate.is_dir():
            return candidate
    raise ExportError(f"no run {run!r}: give 'latest', a run directory or a run id under {runs_dir}")


def _qos(spec: Any) -> list[Any]:
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

    q = spec.qos
    return [Qos(QosHistory.KEEP_LAST, q.depth,
                QosReliability.RELIABLE if q.reliability == "reliable" else QosReliability.BEST_EFFORT,
                QosDurability.TRANSIENT_LOCAL if q.durability == "transient_local" else QosDurability.VOLATILE,
                QosTime(0, 0), QosTime(0, 0), QosLiveliness.AUTOMATIC, QosTime(0, 0), False)]


def export_mcap(run_dir: Path, out: Path, scene: str | Path | None = None) -> dict[str, Any]:
    """Write ``out``; returns a summary (messages per topic, time span)."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    result_file = run_dir / "result.json"
    if not result_file.exists():
        raise ExportError(f"{run_dir} has no result.json: the run is still going or did not start; "
                          "export it once `chronav launch` has finished")
    try:
        result = json.loads(result_file.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ExportError(f"{result_file}: cannot read it as JSON ({exc})") from None
    scene_ref = scene or result.get("scene_path")
    if not scene_ref:
        raise ExportError(f"{result_file} does not name the run's scene file; give it with --scene FILE")
    world = load_world(scene_ref)
    spec = world.scene
    trajectory_csv = run_dir / "trajectory.csv"
    if not trajectory_csv.exists():
        raise ExportError(f"{trajectory_csv} is missing: the robot never drove in this run, there is nothing to "
                          "export")
    try:
        traj = read_trajectory_csv(trajectory_csv)
        people = read_people_csv(run_dir / "people.csv") if (run_dir / "people.csv").exists() else None
        plans = read_plans(run_dir / PLANS_FILE) if (run_dir / PLANS_FILE).exists() else None
    except MetricsInputError as exc:
        raise ExportError(str(exc)) from None
    if len(traj) == 0:
        raise ExportError(f"{trajectory_csv} has no samples: the robot never drove in this run")
    epoch = msgs.day_epoch_s(spec.clock.date, spec.clock.timezone)
    fr = Frames()   # the bridge's default frames (REP-105)
    maps = RosMaps(spec)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    counts: dict[str, int] = {}
    with tempfile.TemporaryDirectory(dir=out.parent) as tmp:
        bag = Path(tmp) / "bag"
        store = typestore()
        with Writer(bag, version=8, storage_plugin=StoragePlugin.MCAP) as writer:
            connections: dict[str, Any] = {}
            pending: list[tuple[int, int, str, bytes]] = []

            def write(key: str, type_name: str, t_s: float, message: Any) -> None:
                topic = getattr(TOPICS, key)
                if key not in connections:
                    connections[key] = writer.add_connection(topic.name, type_name, typestore=store,
                                                             offered_qos_profiles=_qos(topic))
                stamp = msgs.ros_time(t_s, epoch)
                pending.append((stamp.sec * 1_000_000_000 + stamp.nanosec, len(pending), key,
                                serialize(message, type_name)))
                counts[topic.name] = counts.get(topic.name, 0) + 1

            t0 = float(traj[0, 0])
            stamp0 = msgs.ros_time(t0, epoch)
            building = maps.building()
            write("map", msgs.OCCUPANCY_GRID, t0, msgs.occupancy_grid(building.values, building.origin,
                                                                     building.resolution, stamp0, fr.map))
            _drives(traj, world, maps, epoch, fr, write)
            _robot(traj, epoch, fr, write)
            if people is not None:
                _people(people, epoch, fr, write)
            if plans is not None:
                for plan in plans:
                    write("plan", msgs.PATH, plan.t_s, msgs.path(plan.x, plan.y, msgs.ros_time(plan.t_s, epoch), fr.map))
            for log_ns, _, key, data in sorted(pending):   # in log-time order, as a recorder writes
                writer.write(connections[key], log_ns, data)
        produced = next(bag.glob("*.mcap"))
        shutil.move(str(produced), out)
    return {"out": str(out), "messages": counts, "start_s": float(traj[0, 0]), "end_s": float(traj[-1, 0])}


def _drives(traj: np.ndarray, world: Any, maps: RosMaps, epoch: float, fr: Any, write: Any) -> None:
    starts = [0, *(int(i) + 1 for i in np.nonzero(np.diff(traj[:, 0]) > NEW_DRIVE_GAP_S)[0])]
    for i in starts:
        t, x, y, theta = (float(v) for v in traj[i])
        graph = graph_at(world, t, (x, y, theta))
        costmap, keepout = maps.social(maps.nav.build(graph, t))
        stamp = msgs.ros_time(t, epoch)
        for key, grid in (("social_costmap", costmap), ("keepout_filter_mask", keepout)):
            write(key, msgs.OCCUPANCY_GRID, t, msgs.occupancy_grid(grid.values, grid.origin, grid.resolution, stamp,
                                                                   fr.map))
        write("agenda", msgs.STRING, t, msgs.string(msgs.agenda_json(activities(graph))))


def _robot(traj: np.ndarray, epoch: float, fr: Any, write: Any) -> None:
    for i, (t, x, y, theta) in enumerate(traj):
        if 0 < i and traj[i, 0] - traj[i - 1, 0] <= NEW_DRIVE_GAP_S:
            dt = float(traj[i, 0] - traj[i - 1, 0]) or 1e-9
            dx, dy = traj[i, 1] - traj[i - 1, 1], traj[i, 2] - traj[i - 1, 2]
            v = (dx * math.cos(theta) + dy * math.sin(theta)) / dt
            vy = (-dx * math.sin(theta) + dy * math.cos(theta)) / dt
            omega = wrap_angle(float(traj[i, 3] - traj[i - 1, 3])) / dt
        else:
            v = vy = omega = 0.0
        stamp = msgs.ros_time(float(t), epoch)
        write("clock", msgs.CLOCK, t, msgs.clock(stamp))
        write("odom", msgs.ODOMETRY, t, msgs.odometry(x, y, theta, v, vy, omega, stamp, fr.odom, fr.base))
        write("tf", msgs.TF, t, msgs.tf_message([msgs.transform(fr.map, fr.odom, 0.0, 0.0, 0.0, stamp),
                                                 msgs.transform(fr.odom, fr.base, x, y, theta, stamp)]))


@dataclass(frozen=True, slots=True)
class _Person:
    """What ``msgs.people`` reads of a person, from a people.csv row (no interactions recorded there)."""

    name: str
    role: str
    x: float
    y: float
    theta: float
    vx: float
    vy: float
    interacting_with: tuple[str, ...] = ()


def _people(tracks: Any, epoch: float, fr: Any, write: Any) -> None:
    roles = tracks.roles or ("",) * len(tracks.names)
    for k, t in enumerate(tracks.times):
        present = [_Person(name=name, role=roles[j], x=float(tracks.x[k, j]), y=float(tracks.y[k, j]),
                           theta=float(tracks.theta[k, j]), vx=float(tracks.vx[k, j]), vy=float(tracks.vy[k, j]))
                   for j, name in enumerate(tracks.names) if math.isfinite(tracks.x[k, j])]
        stamp = msgs.ros_time(float(t), epoch)
        write("people", msgs.PEOPLE, float(t), msgs.people(present, stamp, fr.map))
        write("tf", msgs.TF, float(t), msgs.tf_message([msgs.transform(fr.map, f"{fr.person_prefix}{p.name}", p.x,
                                                                       p.y, p.theta, stamp) for p in present]))

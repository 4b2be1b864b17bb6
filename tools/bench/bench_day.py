"""Benchmark of a whole day in the centre: every agent as a process, the people living their day.

Prints ONE flat JSON object:

- ``sim_speedup``: sim seconds of the day (clock start to end) per wall second of the run (goal:
  >= 10 on 2 cores with 20 moving people), with ``sim_s``, ``wall_s``, ``people_moving`` (people
  whose routine walks) and ``missions_done`` / ``missions``;
- ``cpu_s_total`` and ``cpu_share_percent_of_<N>_cores``: the agents' CPU time (the router, every
  agent and their children, from the launcher's rusage) and that time as a share of the machine's
  cores over the run; ``cpu_s_<agent>``: per agent process, sampled with psutil while it runs;
- ``crowd_day_replay_s``: wall time to replay the crowd's whole day offline (agents/world/people.py:
  what `chronav path --at 17:59` pays once per scene before it can plan);
- ``collisions``, ``robot_intimate_entries``: summed over the missions from the run's trajectory.csv
  and people.csv (agents/lib/metrics/dynamic_metrics.py).

Run: ``.venv/bin/python tools/bench/bench_day.py [--scene center_day] [--rate R]`` (it launches the
system in a temporary directory; the run's recording is kept there if ``--keep`` is given).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import psutil

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from agents.world.people import people_at
from agents.world.scene_world import load_world
from agents.world.vocabulary import MissionState, vocabulary

#: agent name by the module its process runs (``python -m <module>``), every registered agent's
PROCESS_MODULES = {f"-m {spec.process} ": spec.name for spec in vocabulary().agents}


def _sample_cpu(root: int, stop: threading.Event, seen: dict[int, tuple[str, float]]) -> None:
    """The CPU time of every descendant of ``root``, by agent, until ``stop`` (last value per pid)."""
    while not stop.is_set():
        try:
            children = psutil.Process(root).children(recursive=True)
        except psutil.NoSuchProcess:
            return
        for child in children:
            try:
                cmdline = " ".join(child.cmdline())
                times = child.cpu_times()
            except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
                continue
            name = next((a for m, a in PROCESS_MODULES.items() if m in f"{cmdline} "),
                        "router" if "dsr.router" in cmdline else "")
            if name:
                seen[child.pid] = (name, times.user + times.system)
        stop.wait(0.5)


def run(scene: str, rate: float | None, keep: Path | None) -> dict[str, object]:
    world = load_world(scene)
    clock = world.scene.clock
    moving = sum(1 for p in world.scene.people if p.routine != "stay")
    started = time.perf_counter()
    people_at(world, clock.end_s - 1.0)
    replay_s = time.perf_counter() - started

    workdir = keep or Path(tempfile.mkdtemp(prefix="chronav-bench-day-"))
    workdir.mkdir(parents=True, exist_ok=True)
    command = [sys.executable, "-m", "tools.cli", "launch", str(world.path), "--json", "--timeout", "3000"]
    if rate is not None:
        command += ["--rate", str(rate)]
    env = {**os.environ, "RERUN": os.environ.get("RERUN", "off"),
           "PYTHONPATH": os.pathsep.join([str(Path(__file__).resolve().parents[2]), os.environ.get("PYTHONPATH", "")])}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    wall0 = time.perf_counter()
    process = subprocess.Popen(command, cwd=workdir, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)
    seen: dict[int, tuple[str, float]] = {}
    stop = threading.Event()
    sampler = threading.Thread(target=_sample_cpu, args=(process.pid, stop, seen), daemon=True)
    sampler.start()
    out, err = process.communicate()
    wall = time.perf_counter() - wall0
    stop.set()
    sampler.join()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        result = json.loads(out)
    except json.JSONDecodeError:
        raise SystemExit(f"bench_day: the launch printed no result (exit {process.returncode}):\n{err[-2000:]}") from None
    missions = result.get("missions", {})
    cpu_total = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    cores = psutil.cpu_count() or 1
    report: dict[str, object] = {
        "scene": world.scene.name, "people": len(world.scene.people), "people_moving": moving,
        "sim_s": clock.end_s - clock.start_s, "wall_s": round(wall, 1),
        "sim_speedup": round((clock.end_s - clock.start_s) / wall, 1),
        "missions": len(missions), "missions_done": sum(1 for m in missions.values() if m.get("state") == MissionState.DONE),
        "cpu_s_total": round(cpu_total, 1), f"cpu_share_percent_of_{cores}_cores": round(100 * cpu_total / (wall * cores), 1),
        "crowd_day_replay_s": round(replay_s, 1), "outcome": result.get("outcome"),
    }
    per_agent: dict[str, float] = {}
    for name, cpu in seen.values():
        per_agent[name] = per_agent.get(name, 0.0) + cpu
    report.update({f"cpu_s_{name}": round(cpu, 1) for name, cpu in sorted(per_agent.items())})
    run_dir = Path(result.get("run_dir", ""))
    if (run_dir / "trajectory.csv").exists() and (run_dir / "people.csv").exists():
        from agents.lib.metrics.metrics import read_people_csv, read_trajectory_csv
        from agents.world.offline import SceneMaps

        maps = SceneMaps.load(world)
        trajectory, tracks = read_trajectory_csv(run_dir / "trajectory.csv"), read_people_csv(run_dir / "people.csv")
        collisions = entries = 0
        for mission in missions.values():
            if mission.get("state") != MissionState.DONE or "started_s" not in mission:
                continue
            rows = trajectory[(trajectory[:, 0] >= mission["started_s"]) & (trajectory[:, 0] <= mission["finished_s"])]
            if len(rows) < 2:
                continue
            dynamic = maps.measure(rows, float(mission["started_s"]), tracks).dynamic
            assert dynamic is not None   # measured with the people's tracks: the dynamic metrics are there
            collisions += dynamic.robot_on_person_collisions + dynamic.person_on_robot_collisions
            entries += dynamic.robot_intimate_entries
        report.update({"collisions": collisions, "robot_intimate_entries": entries})
    return report


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="center_day")
    parser.add_argument("--rate", type=float, default=None, help="sim seconds per wall second (default: the scene's)")
    parser.add_argument("--keep", type=Path, default=None, help="run in this directory and keep the recording")
    args = parser.parse_args()
    print(json.dumps(run(args.scene, args.rate, args.keep)))


if __name__ == "__main__":
    main()

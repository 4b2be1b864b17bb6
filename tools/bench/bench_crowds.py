"""Benchmark of recorded crowds: building a scene from a recording, and replaying a crowd in-process.

Prints ONE flat JSON object:
  from_crowd_s_10k         ``chronav scene from-crowd``'s work on a 10,010-row recording (the shipped
                           crowds_zara03 twice, the copy later in time with other ids): read and
                           check the file, plan the plaza and 3 missions, write the scene and check it
                           as ``chronav scene check`` does (imports excluded; goal < 2 s)
  from_crowd_rows          the recording's rows
  replay_people            people walking at once in the replayed-crowd run (40)
  replay_sim_speedup_40    sim seconds per wall second of an in-process run (``chronav launch
                           --in-process``, no recording) of a from-crowd scene where 40 recorded
                           people cross a plaza at once, replayed ``--replay`` (default reactive),
                           measured over the run's driving (trajectory.csv's span over the wall time
                           of the whole run, setup included; goal >= 50)
  replay_wall_s            that run's wall time
  replay_cpu_s             the CPU time this process spent on that run (all its threads): what the
                           run costs whatever else the machine runs (a shared machine's wall time
                           counts the other processes too)
  replay_sim_speedup_40_cpu  sim seconds per CPU second of that run (the same span over replay_cpu_s)
  replay_cpu_s_warm        the CPU time of the same run again in the same process (``--warm``): what
                           each further run of a study costs, the imports, compiled kernels and
                           the scene's caches loaded by the first (a cold run's extra is those)
  replay_sim_speedup_40_cpu_warm  sim seconds per CPU second of that second run
  replay_record            1 when the run wrote its Rerun recording (``--record``), 0 with none (the default,
                           as ``--no-record``)

Run: ``.venv/bin/python tools/bench/bench_crowds.py [--replay exact|reactive] [--record] [--skip-from-crowd] [--warm]``
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
ZARA = REPO / "scenes" / "data" / "pedestrians" / "crowds_zara03.txt"


def ten_thousand_rows(out: Path) -> Path:
    """crowds_zara03 and a copy of it after its end (frames shifted past the last one, ids + 1000)."""
    rows = [line.split() for line in ZARA.read_text(encoding="utf-8").splitlines() if line.strip()]
    last = max(float(r[0]) for r in rows)
    copy = [[f"{float(f) + last + 10:.1f}", f"{float(i) + 1000:.1f}", x, y] for f, i, x, y in rows]
    out.write_text("".join("\t".join(r) + "\n" for r in rows + copy), encoding="utf-8")
    return out


def from_crowd_seconds(work: Path) -> dict[str, float]:
    from agents.world.scene_world import load_world
    from scenes.crowd_recording import read_recording
    from scenes.from_crowd import scene_text

    data = ten_thousand_rows(work / "zara_twice.txt")
    out = work / "zara_twice.yaml"
    load_world(REPO / "scenes" / "crowds" / "circle_crossing.yaml")        # imports and compiled code warm
    started = time.perf_counter()
    recording = read_recording(data)
    out.write_text(scene_text([recording], out, "zara_twice", missions=3, seed=0), encoding="utf-8")
    load_world(out)
    return {"from_crowd_s_10k": round(time.perf_counter() - started, 3), "from_crowd_rows": recording.rows}


def forty_walkers(out: Path, people: int = 40, seconds: float = 40.0) -> Path:
    """``people`` walkers crossing a 20 m square at once, 1.0-1.4 m/s, each from a random point on
    its edge to the opposite edge (seeded), recorded for ``seconds`` at 0.4 s."""
    rng = np.random.default_rng(0)
    lines = []
    starts = rng.uniform(1.0, 19.0, people)
    speeds = rng.uniform(1.0, 1.4, people)
    for k in range(int(seconds / 0.4) + 1):
        t = 0.4 * k
        for i in range(people):
            along = min(1.0 + speeds[i] * t, 19.0)
            x, y = (along, starts[i]) if i % 2 == 0 else (starts[i], 20.0 - along)
            lines.append(f"{10 * k}\t{i + 1}\t{x:.4f}\t{y:.4f}")
    out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return out


def replay_speed(work: Path, replay: str, record: bool = False, warm: bool = False) -> dict[str, float]:
    from scenes.crowd_recording import read_recording
    from scenes.from_crowd import scene_text
    from tools.inprocess import run_in_process

    data = forty_walkers(work / "forty.txt")
    scene = work / "forty.yaml"
    scene.write_text(scene_text([read_recording(data)], scene, "forty", missions=1, seed=0, replay=replay),
                     encoding="utf-8")
    cpu = time.process_time()
    result = run_in_process(scene, runs_dir=work / "runs", record=record, timeout_s=600)
    cpu = time.process_time() - cpu
    span = _driven_span(result.run_dir)
    found = {"replay_people": 40, "replay_sim_speedup_40": round(span / result.wall_s, 2),
             "replay_wall_s": round(result.wall_s, 2), "replay_cpu_s": round(cpu, 2),
             "replay_sim_speedup_40_cpu": round(span / cpu, 2), "replay_record": int(record)}
    if warm:
        cpu = time.process_time()
        again = run_in_process(scene, runs_dir=work / "runs", record=record, timeout_s=600)
        cpu = time.process_time() - cpu
        found |= {"replay_cpu_s_warm": round(cpu, 2),
                  "replay_sim_speedup_40_cpu_warm": round(_driven_span(again.run_dir) / cpu, 2)}
    return found


def _driven_span(run_dir: Path) -> float:
    """Sim seconds from the first to the last row of a run's trajectory.csv (NaN with fewer than two)."""
    times = [float(line.split(",")[0]) for line in
             (run_dir / "trajectory.csv").read_text(encoding="utf-8").splitlines()[1:]]
    return times[-1] - times[0] if len(times) > 1 else math.nan


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--replay", choices=("exact", "reactive"), default="reactive")
    parser.add_argument("--record", action="store_true", help="write the run's Rerun recording (default: none)")
    parser.add_argument("--skip-from-crowd", action="store_true", help="only the replayed run")
    parser.add_argument("--warm", action="store_true", help="run the replay twice in this process and report the second too")
    args = parser.parse_args()
    sys.path.insert(0, str(REPO))
    with tempfile.TemporaryDirectory(prefix="chronav-bench-crowds-") as tmp:
        work = Path(tmp)
        result = {**({} if args.skip_from_crowd else from_crowd_seconds(work)),
                  **replay_speed(work, args.replay, args.record, args.warm)}
    print(json.dumps(result))


if __name__ == "__main__":
    main()

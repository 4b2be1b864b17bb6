"""Write a scene's simulated people as a ``people.csv`` over a stretch of its day, without a run.

Why: a run's ``people.csv`` holds the people only while the robot drives (a few minutes of a
day), so few windows show someone on the way to an activity.  The offline world
(``agents/world/people.people_at``: the simulator's crowd, same seed, without the robot) gives
every person at every moment, to measure the prediction on a whole morning with ``chronav predict
evaluate FILE --scene SCENE`` (docs/prediction.md).  Header and units as the simulator's file.

Run: ``.venv/bin/python tools/offline_people.py SCENE --from 09:30 --to 11:00 --out people.csv [--every 0.4]``
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene")
    parser.add_argument("--from", dest="start", required=True, help="HH:MM[:SS]")
    parser.add_argument("--to", dest="end", required=True, help="HH:MM[:SS]")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--every", type=float, default=0.4, help="seconds between samples")
    args = parser.parse_args()
    sys.path.insert(0, str(REPO))
    from agents.lib.metrics.metrics import PEOPLE_HEADER
    from agents.world.people import people_at
    from agents.world.scene_world import load_world
    from scenes.clock import parse_clock
    from scenes.loader import resolve_scene_path

    if not args.every > 0:
        raise SystemExit("--every must be a positive number of seconds")
    world = load_world(resolve_scene_path(args.scene))
    start, end = parse_clock(args.start), parse_clock(args.end)
    with args.out.open("w", encoding="utf-8") as out:
        out.write(",".join(PEOPLE_HEADER) + "\n")
        k = 0
        while start + k * args.every <= end:
            t = start + k * args.every
            out.writelines(f"{t:.3f},{p.name},{p.role},{p.x:.4f},{p.y:.4f},{p.theta:.5f},{p.vx:.4f},{p.vy:.4f},"
                           f"{getattr(p, 'group', '') or ''}\n" for p in people_at(world, t))
            k += 1


if __name__ == "__main__":
    main()

"""Benchmark: what the extension registry costs (agents/lib/registry.py).

Prints one flat JSON object.  Why these keys: the registry must not slow a run (issue 38: under
1 % of bench_day's wall time) nor `chronav --help` (at most 50 ms).  A run pays the metadata scan
once per process and kind (``registry_first_scan_ms``); every later lookup is a dict read
(``registry_cached_lookup_us``, ``planner_cached_lookup_us`` as plan() does it once per plan).
``help_wall_ms`` / ``help_cpu_ms`` are `chronav --help` in a fresh process (it imports no registry).
``agents_vocabulary_ms``: what every agent process and launch pays once at start to read the
``chronav.agents`` entries and take what they declare into the vocabulary (fresh process, the
vocabulary module already imported); ``vocabulary_check_us``: one checked write's vocabulary
check (the merged vocabulary is cached: a dict read).

    python tools/bench/bench_registry.py [--repeat N]
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

FIRST_SCAN = ("import time; t = time.perf_counter(); from agents.lib import registry; "
              "a = time.perf_counter(); registry.extensions('planner'); b = time.perf_counter(); "
              "print((a - t) * 1e3, (b - a) * 1e3)")


AGENTS_VOCABULARY = ("import time; from agents.world import vocabulary as v; t = time.perf_counter(); "
                     "v.vocabulary(); print((time.perf_counter() - t) * 1e3)")


def _fresh(code: str) -> list[float]:
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    return [float(v) for v in out.stdout.split()]


def _help_ms() -> tuple[float, float]:
    """(wall, CPU) ms of `chronav --help` in a fresh process; CPU (user + system) is what to compare
    on a shared machine, where the wall time carries the other processes' load."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "tools.cli", "--help"], cwd=ROOT, capture_output=True, check=True)
    wall = (time.perf_counter() - started) * 1e3
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime) * 1e3


def _per_call_us(call: object, n: int = 20_000) -> float:
    assert callable(call)
    started = time.perf_counter()
    for _ in range(n):
        call()
    return (time.perf_counter() - started) / n * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7, help="fresh processes per wall-time key (median)")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    from agents.lib import registry
    from agents.lib.planning.planners import planner

    from agents.world.vocabulary import check_attrs

    fresh = [_fresh(FIRST_SCAN) for _ in range(args.repeat)]
    agents = [_fresh(AGENTS_VOCABULARY)[0] for _ in range(args.repeat)]
    planner("social")
    helps = [_help_ms() for _ in range(args.repeat)]
    results = {
        "registry_import_ms": round(statistics.median(f[0] for f in fresh), 2),
        "registry_first_scan_ms": round(statistics.median(f[1] for f in fresh), 2),
        "registry_cached_lookup_us": round(_per_call_us(lambda: registry.extensions("planner")), 3),
        "registry_cached_load_us": round(_per_call_us(lambda: registry.load("planner", "social")), 3),
        "planner_cached_lookup_us": round(_per_call_us(lambda: planner("social")), 3),
        "agents_vocabulary_ms": round(statistics.median(agents), 2),
        "vocabulary_check_us": round(_per_call_us(lambda: check_attrs("clock", {"now_s": 1.0})), 3),
        "help_wall_ms": round(statistics.median(h[0] for h in helps), 1),
        "help_cpu_ms": round(statistics.median(h[1] for h in helps), 1),
    }
    print(json.dumps(results))


if __name__ == "__main__":
    main()

"""DSR receive-path benchmark, in one process: prints ONE flat JSON object.

Why separate from bench_dsr.py: the join and update numbers there are wall-clock times across
processes, which the shared 2-core machine makes noisy; this one times only what a receiver
does with a payload, in CPU time (best of --repeat), and times a bare orjson.loads of the same
payloads in the same run (a parse without any validation: the floor any JSON decoder starts
from), so the two compare on equal terms.

- decode_10k_ms: wire.decode() of every part of the state of bench_dsr.py's 10k-node join graph
  (`state_parts()`); parse_10k_orjson_ms: orjson.loads of the same parts; merge_10k_ms: apply_message() of the decoded parts into an empty read-only
  graph (gc disabled while timing, as in a join's burst);
- decode_update_us / parse_update_orjson_us: one single-attribute update delta;
- state_parts, state_bytes: the size of what is decoded.

Usage: python tools/bench/bench_dsr_decode.py [--nodes 10000] [--repeat 7]
"""

from __future__ import annotations

import argparse
import gc
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))


def _best_s(action: Callable[[], object], repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.thread_time()
        kept = action()      # freed after the clock stops: deallocation is not decoding
        best = min(best, time.thread_time() - start)
        del kept
        gc.collect()
    return best


def _paired(new: Callable[[], object], old: Callable[[], object],
            repeat: int) -> tuple[float, float]:
    """Best times of the two, measured alternately (the machine's load hits both alike)."""
    best_new = best_old = float("inf")
    for _ in range(repeat):
        best_new = min(best_new, _best_s(new, 1))
        best_old = min(best_old, _best_s(old, 1))
    return best_new, best_old


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--nodes", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args(argv)

    import orjson

    from dsr import DSRGraph, wire
    from tools.bench.bench_dsr import fill_graph
    writer = DSRGraph("w")
    fill_graph(writer, args.nodes)
    parts = list(writer.state_parts())
    updates: list[bytes] = []
    writer.attach(updates.append, linger_s=0.0)
    node_id = writer.require_node("marker").id
    for i in range(2000):
        writer.update_node(node_id, {"seq": i})
    writer.attach(None)

    def merge() -> None:
        decoded = [wire.decode(part) for part in parts]
        reader = DSRGraph("r", read_only=True)
        start = time.thread_time()
        for message in decoded:
            reader.apply_message(message)
        merge_s.append(time.thread_time() - start)
        if len(reader) != len(writer):
            raise RuntimeError(f"bench: merged {len(reader)} nodes of {len(writer)}")

    old = orjson.loads

    gc.disable()
    merge_s: list[float] = []
    for _ in range(args.repeat):
        merge()
        gc.collect()
    new_s, old_s = _paired(lambda: [wire.decode(p) for p in parts],
                           lambda: [old(p) for p in parts], args.repeat)
    update_s, update_old_s = _paired(lambda: [wire.decode(p) for p in updates],
                                     lambda: [old(p) for p in updates], 10 * args.repeat)
    result = {
        "decode_10k_ms": 1e3 * new_s, "parse_10k_orjson_ms": 1e3 * old_s,
        "merge_10k_ms": 1e3 * min(merge_s),
        "decode_update_us": 1e6 * update_s / len(updates),
        "parse_update_orjson_us": 1e6 * update_old_s / len(updates),
        "state_parts": len(parts), "state_bytes": sum(map(len, parts)), "nodes": len(writer)}
    gc.enable()
    print(json.dumps({k: (round(v, 3) if isinstance(v, float) else v)
                      for k, v in result.items()}))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""A scripted replica process for the multi-process DSR tests (tests/integration/dsr_support.py).

`python -m tests.integration.replica_worker --connect tcp/127.0.0.1:PORT --agent a --status a.json
 [--ops 300 --seed 1] [--world 500]`

It joins the graph, optionally inserts a world of N nodes, performs N random operations
(inserts, attribute updates, deletes, edge inserts/deletes, some grouped in transactions, some
on a shared pool of names to provoke concurrent name clashes), then keeps serving until SIGTERM.
Every 50 ms it rewrites `--status` (atomically) with its graph digest, sizes and replica stats,
so a test can wait for convergence without sharing memory with the process.
"""

from __future__ import annotations

import argparse
import gc
import os
import random
import sys
import time
from pathlib import Path
from typing import Any

import orjson

from dsr.config import ZenohSettings
from dsr.errors import DSRError
from dsr.graph import DSRGraph
from dsr.process import exit_on_sigterm
from dsr.transport import join

NODE_TYPES = ("room", "person", "object", "activity")
EDGE_TYPES = ("RT", "in", "interacting")


def write_status(path: Path, graph: DSRGraph, done: bool, ops: dict[str, int]) -> None:
    replica = graph.replica
    status: dict[str, Any] = {
        "agent": graph.agent, "pid": os.getpid(), "done": done, "digest": graph.digest(),
        "nodes": len(graph), "edges": len(graph.edges()), "ops": ops,
        "names": sorted(n.name for n in graph.nodes()),
        "stats": replica.stats.as_dict() if replica is not None else {},
        "gc_threshold": gc.get_threshold(),
    }
    tmp = path.with_suffix(".tmp")
    tmp.write_bytes(orjson.dumps(status))
    os.replace(tmp, path)


def random_op(graph: DSRGraph, rng: random.Random, counter: int, ops: dict[str, int]) -> None:
    nodes = graph.nodes()
    roll = rng.random()
    if roll < 0.30 or len(nodes) < 3:
        name = f"shared-{rng.randrange(8)}" if rng.random() < 0.1 else f"{graph.agent}-{counter}"
        graph.insert_node(rng.choice(NODE_TYPES), name, {"made_by": graph.agent, "n": counter})
        kind = "insert_node"
    elif roll < 0.65:
        node = rng.choice(nodes)
        graph.update_node(node.id, {rng.choice("abc"): rng.random(),
                                    "tags": [graph.agent, str(counter)]})
        kind = "update_node"
    elif roll < 0.72:
        graph.delete_node(rng.choice(nodes).id)
        kind = "delete_node"
    elif roll < 0.92:
        src, dst = rng.sample(nodes, 2)
        graph.insert_or_assign_edge(src.id, dst.id, rng.choice(EDGE_TYPES),
                                    {"x": rng.random(), "y": rng.random(), "theta": 0.0})
        kind = "insert_edge"
    else:
        edges = graph.edges()
        if not edges:
            return
        edge = rng.choice(edges)
        graph.delete_edge(edge.src, edge.dst, edge.type)
        kind = "delete_edge"
    ops[kind] = ops.get(kind, 0) + 1


def run(args: argparse.Namespace) -> int:
    settings = ZenohSettings(connect=[args.connect])
    status_path = Path(args.status)
    rng = random.Random(args.seed)
    ops: dict[str, int] = {}
    with join(args.agent, graph=args.graph, settings=settings) as graph:
        graph.connect("node_added", lambda node: None)
        if args.world:
            with graph.transaction():
                for i in range(args.world):
                    graph.insert_node(rng.choice(NODE_TYPES), f"{args.agent}-w{i}", {"i": i})
        last_status = 0.0
        for counter in range(args.ops):
            try:
                if rng.random() < 0.2:
                    with graph.transaction():
                        for sub in range(rng.randint(1, 4)):
                            random_op(graph, rng, counter * 10 + sub, ops)
                else:
                    random_op(graph, rng, counter, ops)
            except DSRError as exc:  # a remote delete raced our choice: expected
                ops[type(exc).__name__] = ops.get(type(exc).__name__, 0) + 1
            graph.dispatch()
            if args.pause_ms:
                time.sleep(rng.random() * args.pause_ms / 1000.0)
            if time.monotonic() - last_status > 0.05:
                write_status(status_path, graph, False, ops)
                last_status = time.monotonic()
        while True:
            graph.dispatch(timeout=0.05)
            write_status(status_path, graph, True, ops)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.integration.replica_worker",
                                     description=__doc__)
    parser.add_argument("--connect", required=True)
    parser.add_argument("--agent", required=True)
    parser.add_argument("--graph", default="chronav")
    parser.add_argument("--status", required=True)
    parser.add_argument("--ops", type=int, default=0)
    parser.add_argument("--world", type=int, default=0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--pause-ms", type=float, default=2.0)
    args = parser.parse_args(argv)
    exit_on_sigterm()
    try:
        return run(args)
    except (KeyboardInterrupt, SystemExit):
        return 0


if __name__ == "__main__":
    sys.exit(main())

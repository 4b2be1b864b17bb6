"""A scripted DSR replica process for the fault and trust tests (not a test module).

`python -m tests.integration.replica_script --agent A --status S [--script JSON] [--writes N]`

- Zenoh settings and the write policy come from the environment (CHRONAV_ZENOH_*,
  CHRONAV_WRITE_POLICY), exactly like an agent; `--connect` overrides the endpoint.
- `--script` runs a JSON list of steps once joined: `{"op": "insert", "type", "name", "attrs"}`,
  `{"op": "update", "name", "attrs"}`, `{"op": "edge", "src", "dst", "type", "attrs"}`,
  `{"op": "delete", "name"}`, `{"op": "wait", "names": [...]}` (until those nodes are visible).
- `--writes N` then performs N *monotonic* writes, one every `--period-ms`: write k inserts node
  `<agent>-<k>` and sets `<agent>-counter.k = k`.  A write is "acknowledged" once applied to the
  local replica; since nothing ever deletes these nodes, a converged replica must hold every
  acknowledged node of every writer and each counter at its writer's last k.
- Every 50 ms the status file is rewritten atomically: stats, `acked`, a history of (wall time,
  acked, deltas received) from which tests compute loop rates, and (at most every 0.25 s, and
  never while writing with `--measure`) the O(graph) view: digest, names, counters.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

import orjson

from dsr.config import ZenohSettings
from dsr.graph import DSRGraph
from agents.world.write_policy import policy_from_env
from dsr.process import exit_on_sigterm
from dsr.transport import join

STATUS_PERIOD_S = 0.05
DIGEST_PERIOD_S = 0.25   # the digest is O(graph): at most 4 per second, only after changes


class Status:
    def __init__(self, path: Path, graph: DSRGraph) -> None:
        self.path, self.graph = path, graph
        self.acked = 0
        self.script_done = False
        self.done = False
        self.writing = False     # no O(graph) digest while measuring the writer's loop rate
        self.history: list[tuple[float, int, int]] = []   # (wall time, acked, received)
        self.last = 0.0
        self._view: dict[str, Any] = {}
        self._view_at = -1.0
        self._view_version = -1

    def maybe_write(self, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now - self.last < STATUS_PERIOD_S:
            return
        self.last = now
        graph = self.graph
        replica = graph.replica
        received = replica.stats.received if replica is not None else 0
        self.history.append((time.time(), self.acked, received))
        del self.history[:-2000]
        if not self.writing and graph.version != self._view_version \
                and (force or now - self._view_at >= DIGEST_PERIOD_S):
            self._view_version, self._view_at = graph.version, now
            nodes = graph.nodes()
            self._view = {"digest": graph.digest(), "nodes": len(nodes),
                          "names": sorted(n.name for n in nodes),
                          "counters": {n.name: n.attrs.get("k") for n in nodes
                                       if n.name.endswith("-counter")}}
        status: dict[str, Any] = {
            "agent": graph.agent, "pid": os.getpid(), **self._view,
            "stats": replica.stats.as_dict() if replica is not None else {},
            "acked": self.acked, "script_done": self.script_done, "done": self.done,
            "history": self.history,
        }
        tmp = self.path.with_suffix(".tmp")
        tmp.write_bytes(orjson.dumps(status))
        os.replace(tmp, self.path)


def run_step(graph: DSRGraph, step: dict[str, Any], status: Status) -> None:
    op = step["op"]
    if op == "insert":
        graph.insert_node(step["type"], step["name"], step.get("attrs") or {})
    elif op == "update":
        graph.update_node(graph.require_node(step["name"]).id, step["attrs"])
    elif op == "edge":
        graph.insert_or_assign_edge(graph.require_node(step["src"]).id,
                                    graph.require_node(step["dst"]).id, step["type"],
                                    step.get("attrs") or {})
    elif op == "delete":
        graph.delete_node(graph.require_node(step["name"]).id)
    elif op == "wait":
        deadline = time.monotonic() + float(step.get("timeout", 20))
        while any(graph.get_node_by_name(n) is None for n in step["names"]):
            if time.monotonic() > deadline:
                raise TimeoutError(f"nodes {step['names']} never appeared")
            graph.dispatch(timeout=0.02)
            status.maybe_write()
    else:
        raise ValueError(f"unknown step op {op!r}")


def monotonic_writes(graph: DSRGraph, count: int, period_s: float, payload: int,
                     status: Status) -> None:
    counter = graph.insert_node("object", f"{graph.agent}-counter", {"k": -1})
    filler = [0.5] * payload
    next_at = time.monotonic()
    for k in range(count):
        with graph.transaction():
            graph.insert_node("object", f"{graph.agent}-{k}", {"k": k, "data": filler})
            graph.update_node(counter.id, {"k": k})
        status.acked = k + 1
        status.maybe_write()
        next_at += period_s
        delay = next_at - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        else:
            next_at = time.monotonic()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.integration.replica_script")
    parser.add_argument("--agent", required=True)
    parser.add_argument("--status", required=True, type=Path)
    parser.add_argument("--graph", default="chronav")
    parser.add_argument("--connect", default=None)
    parser.add_argument("--script", default="[]", help="JSON list of steps")
    parser.add_argument("--writes", type=int, default=0)
    parser.add_argument("--period-ms", type=float, default=5.0)
    parser.add_argument("--payload", type=int, default=0, help="floats per monotonic write")
    parser.add_argument("--measure", action="store_true",
                        help="no O(graph) status view while writing (clean loop-rate numbers)")
    args = parser.parse_args(argv)
    exit_on_sigterm()
    settings = ZenohSettings.from_env()
    if args.connect:
        settings = settings.model_copy(update={"connect": [args.connect]})
    try:
        with join(args.agent, graph=args.graph, settings=settings,
                  policy=policy_from_env()) as graph:
            status = Status(args.status, graph)
            for step in orjson.loads(args.script):
                run_step(graph, step, status)
                graph.dispatch()
            status.script_done = True
            if args.writes:
                status.writing = args.measure
                monotonic_writes(graph, args.writes, args.period_ms / 1000.0, args.payload,
                                 status)
            status.writing, status.done = False, True
            status.maybe_write(force=True)
            while True:
                graph.dispatch(timeout=STATUS_PERIOD_S)
                status.maybe_write()
    except (KeyboardInterrupt, SystemExit):
        return 0


if __name__ == "__main__":
    sys.exit(main())

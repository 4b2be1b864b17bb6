"""DSR benchmark: prints ONE flat JSON object.

Measures, between two separate OS processes connected through a Python Zenoh router started
here on a free loopback port:
- zenoh_p50_ms / zenoh_p99_ms: bare Zenoh put -> subscriber -> put back round trip;
- dsr_p50_ms / dsr_p99_ms: DSR round trip: driver updates node "ping"; the echo replica gets the
  node_updated signal in its dispatch() loop and updates node "pong"; the driver waits for that
  signal in its own dispatch() loop.  Both numbers are ROUND trips (two propagations);
- dsr_nopoll_p50_ms: the same between a second driver replica and a second echo process whose
  dispatch() never polls (dsr.signals.SpinPolicy window 0, as CHRONAV_DSR_SPIN_US=0 sets):
  what the default polling buys, in the same run.  dispatch_poll_*: the driver's default
  replica during the latency phase: polls that found the answer, polls that gave up, and the
  share of one core spent polling (the echo's is alike); dispatch_received_by_agent: deltas
  its polling thread decoded and merged itself instead of the receiver thread (dsr/receiver.py;
  dsr_nopoll_received_by_agent: the same for the no-poll replica, always 0);
- wire_floor_p50_ms: the same round trip through the DSR wire layer only: each side decodes the
  delta it receives (wire.decode), hands it to another thread as an agent loop does, and that
  thread encodes the answer (DeltaEncoder) and puts it, with the replica's publisher options.
  No graph: no merge, checks, clock, signals or send order.  It is the floor of any Python
  replica of this format with agent-style hand-off on this machine; wire_floor_over_zenoh_p50
  and dsr_over_wire_floor_p50 split dsr_over_zenoh_p50 into the wire layer's share and the
  graph machinery's;
- updates_per_s: sustained single-attribute updates, round robin over 1,000 nodes (so
  coalescing cannot merge them away), until the echo replica has applied the last one and
  delivered its signals.  The writer batches as docs/dsr_wire_format.md says a writer should:
  `update_nodes()` with one update of each of the 1,000 nodes per call (one stamp, one delta);
  local_updates_per_s is the writer's own rate.  single_updates_per_s /
  single_local_updates_per_s: the same with one update_node() call per update (the outbox
  coalesces bursts into fewer samples);
- profile_*: where the time of one update goes, measured in this process on the same code:
  encode (update_node() up to the payload handed to Zenoh), decode (validation), merge
  (apply_message), signal hand-off (receiver thread -> a sleeping dispatch() thread);
  profile_top: the top functions of a cProfile of that path (full listing on stderr);
- join_10k_s: a new process's join() of a graph of 10,000 nodes (~9,000 with an RT edge and
  3 attributes, plus the nodes of the previous phases): session open, member lookup, one full
  state fetched, validated and merged (the other replicas' states follow in the background).
  As in a running system, agents have joined before (each member has served its state once)
  and the graph changed since (a write right before each join): median of 3 joins.
  join_10k_first_s: the first join ever served by the members, which encode every element.

Usage: python tools/bench/bench_dsr.py [--rounds 1000] [--updates 200000] [--join-nodes 10000]
The machine's 2 cores are shared: run it several times and report the best and median run.
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from agents.world.vocabulary import EdgeType, NodeType  # noqa: E402 - after the path fix above

# Plain strings from the vocabulary: this benchmark measures the DSR, whose writes it makes with
# synthetic attributes on these types (it never runs through an agent's checked graph).
OBJECT, WORLD, RT = str(NodeType.OBJECT), str(NodeType.WORLD), str(EdgeType.RT)


def _has_subscribers(publisher: Any) -> bool:
    """Whether a zenoh publisher has a matching subscriber.  ``Any``: zenoh's stub types
    ``matching_status`` as a bool, while at run time it is a MatchingStatus whose ``.matching`` says it."""
    return bool(publisher.matching_status.matching)


def _wait(predicate: Any, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.01)
    raise TimeoutError(f"bench: timed out waiting for {what}")


def _percentile(samples: list[float], q: float) -> float:
    ordered = sorted(samples)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


# ---------------------------------------------------------------- echo process
def run_echo(endpoint: str, graph_name: str, poll: bool = True) -> None:
    """The echo side; with poll=False only a DSR echo whose dispatch() never polls."""
    import zenoh

    from dsr import SpinPolicy, ZenohSettings, join
    from dsr.process import exit_on_sigterm
    exit_on_sigterm()
    settings = ZenohSettings(connect=[endpoint])
    raw = zenoh.open(settings.to_zenoh_config())
    try:
        if poll:
            raw_echoes(raw, graph_name)
        spin = None if poll else SpinPolicy(window_us=0)
        with join("echo", graph=graph_name, settings=settings, spin=spin) as graph:
            pong = graph.insert_node(OBJECT, "pong", {"seq": -1})

            def on_updated(node: Any, keys: list[str]) -> None:
                if node.name == "ping" and "seq" in keys:
                    graph.update_node(pong.id, {"seq": node.attrs["seq"]})
                elif node.name == "load_end" and node.attrs.get("last"):
                    graph.update_node(pong.id, {"load_done": node.attrs["i"]})

            def on_added(node: Any) -> None:
                if node.name == "marker":
                    graph.update_node(pong.id, {"synced": len(graph)})

            graph.connect("node_updated", on_updated)
            graph.connect("node_added", on_added)
            while True:
                graph.dispatch(timeout=0.5)
    except (KeyboardInterrupt, SystemExit):
        pass
    finally:
        raw.close()


def raw_echoes(raw: Any, graph_name: str) -> None:
    """Bare Zenoh echoes (direct and with an agent-like hand-off) and the wire-floor echo."""
    import zenoh

    pong_pub = raw.declare_publisher(f"bench/{graph_name}/pong",
                                     congestion_control=zenoh.CongestionControl.BLOCK)
    raw.declare_subscriber(f"bench/{graph_name}/ping",
                           lambda sample: pong_pub.put(sample.payload))
    # the same echo with an agent-like hand-off: callback -> queue -> main thread replies
    handoff: queue.SimpleQueue[bytes] = queue.SimpleQueue()
    tpong_pub = raw.declare_publisher(f"bench/{graph_name}/tpong",
                                      congestion_control=zenoh.CongestionControl.BLOCK)
    raw.declare_subscriber(f"bench/{graph_name}/tping",
                           lambda sample: handoff.put(sample.payload.to_bytes()))

    def handoff_loop() -> None:
        while True:
            tpong_pub.put(handoff.get())
    threading.Thread(target=handoff_loop, daemon=True).start()
    wire_floor_echo(raw, graph_name)


#: the replica id each side of the wire-floor round trip writes with
_WIRE_REPLICA = {"echo": 3, "driver": 5}


def _wire_side(session: Any, graph_name: str, me: str, peer: str) -> tuple[Any, Any, Any]:
    """One side of the wire-floor round trip: a publisher with the replica's options, a
    subscriber that decodes what arrives and queues it, and an encoder."""
    import zenoh

    from dsr import wire
    from dsr.transport import delta_publisher_options
    publisher = session.declare_publisher(f"bench/{graph_name}/wire/{me}",
                                          **delta_publisher_options(zenoh))
    inbox: queue.SimpleQueue[Any] = queue.SimpleQueue()
    session.declare_subscriber(f"bench/{graph_name}/wire/{peer}",
                               lambda sample: inbox.put(wire.decode(sample.payload.to_bytes())))
    return publisher, inbox, wire.DeltaEncoder(graph_name, me, _WIRE_REPLICA[me])


def wire_floor_echo(session: Any, graph_name: str) -> None:
    """Answer each decoded wire-floor delta from another thread: encode, put."""
    publisher, inbox, encoder = _wire_side(session, graph_name, "echo", "driver")

    def loop() -> None:
        stamp = 0
        while True:
            message = inbox.get()
            stamp += 1
            seq = message.nodes[0][1].attrs["seq"][2]
            publisher.put(encoder.node_attrs(2, {"seq": (stamp, _WIRE_REPLICA["echo"], seq)}))
    threading.Thread(target=loop, daemon=True).start()


class WireFloor:
    """The driver's side of the wire-floor round trip (see the module docstring)."""

    def __init__(self, session: Any, graph_name: str) -> None:
        self.publisher, self.inbox, self.encoder = _wire_side(session, graph_name, "driver",
                                                              "echo")
        _wait(lambda: _has_subscribers(self.publisher), 10, "wire-floor echo")

    def round_trip(self, i: int) -> float:
        start = time.perf_counter()
        self.publisher.put(self.encoder.node_attrs(1, {"seq": (i, _WIRE_REPLICA["driver"], i)}))
        message = self.inbox.get(timeout=10)
        if message.nodes[0][1].attrs["seq"][2] != i:
            raise RuntimeError(f"bench: wire-floor echo answered {message.nodes}, not {i}")
        return (time.perf_counter() - start) * 1000


# ---------------------------------------------------------------- joiner process
def run_join(endpoint: str, graph_name: str, hold_s: float = 0.0) -> None:
    from dsr import ZenohSettings, join
    settings = ZenohSettings(connect=[endpoint])
    start = time.perf_counter()
    with join("joiner", graph=graph_name, settings=settings, read_only=True) as graph:
        elapsed = time.perf_counter() - start
        print(json.dumps({"join_s": elapsed, "nodes": len(graph), "edges": len(graph.edges()),
                          "state_replies": graph.replica.stats.state_merged}), flush=True)
        time.sleep(hold_s)   # the background round then fetches every other member's state


# ---------------------------------------------------------------- driver
class Procs:
    def __init__(self) -> None:
        self.procs: list[subprocess.Popen[bytes]] = []

    def spawn(self, args: list[str], stdout: Any = subprocess.DEVNULL) -> subprocess.Popen[bytes]:
        proc = subprocess.Popen([sys.executable, *args], cwd=REPO, stdout=stdout,
                                stderr=subprocess.DEVNULL, start_new_session=True)
        self.procs.append(proc)
        return proc

    def close(self) -> None:
        for proc in self.procs:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGTERM)
        for proc in self.procs:
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait(timeout=5)


class BareZenoh:
    """Bare Zenoh round trips: `direct` (echo replies inside its callback, driver blocks in
    recv()) and `handoff` (both sides pass the sample to another Python thread, as an agent
    loop does)."""

    def __init__(self, endpoint: str, graph_name: str) -> None:
        import zenoh

        from dsr import ZenohSettings
        self.session = zenoh.open(ZenohSettings(connect=[endpoint]).to_zenoh_config())
        block = zenoh.CongestionControl.BLOCK
        self.sub = self.session.declare_subscriber(f"bench/{graph_name}/pong")
        self.pub = self.session.declare_publisher(f"bench/{graph_name}/ping",
                                                  congestion_control=block)
        self.handoff: queue.SimpleQueue[bytes] = queue.SimpleQueue()
        self.tsub = self.session.declare_subscriber(
            f"bench/{graph_name}/tpong", lambda sample: self.handoff.put(sample.payload.to_bytes()))
        self.tpub = self.session.declare_publisher(f"bench/{graph_name}/tping",
                                                   congestion_control=block)
        _wait(lambda: _has_subscribers(self.pub) and _has_subscribers(self.tpub), 10, "echo subscribers")

    def direct(self, i: int) -> float:
        start = time.perf_counter()
        self.pub.put(str(i))
        self.sub.recv()
        return (time.perf_counter() - start) * 1000

    def threaded(self, i: int) -> float:
        start = time.perf_counter()
        self.tpub.put(str(i))
        self.handoff.get(timeout=10)
        return (time.perf_counter() - start) * 1000

    def close(self) -> None:
        self.session.close()


class DsrPing:
    def __init__(self, graph: Any) -> None:
        _wait(lambda: graph.get_node_by_name("pong") is not None, 10, "echo replica")
        self.graph = graph
        self.pong_id = graph.get_node_by_name("pong").id
        self.ping = graph.insert_node(OBJECT, "ping", {"seq": -1})
        self.got: dict[str, Any] = {}
        graph.connect("node_updated", self._on_updated)

    def _on_updated(self, node: Any, keys: list[str]) -> None:
        if node.id == self.pong_id:
            for key in keys:
                self.got[key] = node.attrs[key]

    def wait_for(self, key: str, value: Any, timeout: float = 30.0) -> None:
        deadline = time.monotonic() + timeout
        while self.got.get(key) != value:
            if time.monotonic() > deadline:
                raise TimeoutError(f"bench: echo never answered {key}={value}")
            self.graph.dispatch(timeout=0.5)

    def round_trip(self, i: int) -> float:
        start = time.perf_counter()
        self.graph.update_node(self.ping.id, {"seq": i})
        self.wait_for("seq", i)
        return (time.perf_counter() - start) * 1000


def latencies(bare: BareZenoh, floor: WireFloor, ping: DsrPing, nopoll: DsrPing,
              rounds: int) -> dict[str, float]:
    """Interleave blocks of each kind so that all five see the same machine load."""
    samples: dict[str, list[float]] = {"zenoh": [], "zenoh_handoff": [], "wire_floor": [],
                                       "dsr": [], "dsr_nopoll": []}
    block = 50
    seq = 0
    before = ping.graph.dispatch_stats()
    taken = {"dispatch": ping.graph.replica.stats.received_by_agent,
             "dsr_nopoll": nopoll.graph.replica.stats.received_by_agent}
    started = time.perf_counter()
    for blk in range(rounds // block + 1):       # the first block is a warm-up
        for name, fn in (("zenoh", bare.direct), ("zenoh_handoff", bare.threaded),
                         ("wire_floor", floor.round_trip),
                         ("dsr", ping.round_trip), ("dsr_nopoll", nopoll.round_trip)):
            for _ in range(block):
                seq += 1
                value = fn(seq)
                if blk > 0:
                    samples[name].append(value)
    out: dict[str, float] = {}
    for name, values in samples.items():
        out[f"{name}_p50_ms"] = _percentile(values, 0.5)
        out[f"{name}_p99_ms"] = _percentile(values, 0.99)
    after = ping.graph.dispatch_stats()
    out["dispatch_poll_hits"] = after["poll_hits"] - before["poll_hits"]
    out["dispatch_poll_misses"] = after["poll_misses"] - before["poll_misses"]
    out["dispatch_poll_core_share"] = ((after["poll_s"] - before["poll_s"])
                                       / (time.perf_counter() - started))
    out["dispatch_received_by_agent"] = (ping.graph.replica.stats.received_by_agent
                                         - taken["dispatch"])
    out["dsr_nopoll_received_by_agent"] = (nopoll.graph.replica.stats.received_by_agent
                                           - taken["dsr_nopoll"])
    return out


def throughput(ping: DsrPing, updates: int) -> dict[str, float]:
    graph = ping.graph
    with graph.transaction():
        load_ids = [graph.insert_node(OBJECT, f"load{k}", {"i": -1}).id for k in range(1000)]
        load_end = graph.insert_node(OBJECT, "load_end", {"i": -1})
    count = len(load_ids)
    out: dict[str, float] = {}
    # batched: one update_nodes() call updates each of the 1,000 nodes once
    start = time.perf_counter()
    done = 0
    while done < updates - 1:
        batch = min(count, updates - 1 - done)
        graph.update_nodes({load_ids[k]: {"i": done + k} for k in range(batch)})
        done += batch
        graph.dispatch()           # an agent's loop delivers its signals between writes
    graph.update_node(load_end.id, {"i": updates - 1, "last": True})
    local = time.perf_counter() - start
    ping.wait_for("load_done", updates - 1, timeout=120)
    total = time.perf_counter() - start
    out.update({"updates_per_s": updates / total, "local_updates_per_s": updates / local})
    # one update_node() call per update
    single = max(1000, updates // 4)
    start = time.perf_counter()
    for i in range(single - 1):
        graph.update_node(load_ids[i % count], {"i": i})
        if i % count == count - 1:
            graph.dispatch()
    graph.update_node(load_end.id, {"i": updates + single, "last": True})
    local = time.perf_counter() - start
    ping.wait_for("load_done", updates + single, timeout=120)
    total = time.perf_counter() - start
    out.update({"single_updates_per_s": single / total, "single_local_updates_per_s": single / local})
    return out


def profile_split(rounds: int = 20000) -> dict[str, Any]:
    """Where one update's time goes, on the same code paths, in this process."""
    import cProfile
    import io
    import pstats

    from dsr import DSRGraph, wire
    writer, reader = DSRGraph("w"), DSRGraph("r")
    node = writer.insert_node(OBJECT, "n", {"seq": -1})
    reader.apply_message(wire.decode(writer.state_message()))
    payloads: list[bytes] = []
    writer.attach(payloads.append, linger_s=0.0)
    start = time.perf_counter()
    for i in range(rounds):
        writer.update_node(node.id, {"seq": i})
    encode = (time.perf_counter() - start) / rounds
    start = time.perf_counter()
    decoded = [wire.decode(p) for p in payloads]
    decode = (time.perf_counter() - start) / rounds
    reader.connect("node_updated", lambda n, keys: None)
    start = time.perf_counter()
    for message in decoded:
        reader.apply_message(message)
    merge = (time.perf_counter() - start) / rounds
    reader.dispatch()
    # hand-off: post on this thread, a dispatcher thread runs the callback and answers
    answers: queue.SimpleQueue[int] = queue.SimpleQueue()
    hub = DSRGraph("h")
    hub.connect("node_deleted", answers.put)
    stop = threading.Event()

    def loop() -> None:
        while not stop.is_set():
            hub.dispatch(timeout=0.1)
    thread = threading.Thread(target=loop, daemon=True)
    thread.start()
    n = 2000
    start = time.perf_counter()
    for i in range(n):
        hub._signals.post([("node_deleted", (i,))])
        answers.get(timeout=5)
    handoff = (time.perf_counter() - start) / n / 2     # a round trip is two hand-offs
    stop.set()
    thread.join()
    profiler = cProfile.Profile()
    profiler.enable()
    for i in range(rounds // 4):
        writer.update_node(node.id, {"seq": i})
        reader.apply_message(wire.decode(payloads[-1]))
    reader.dispatch()
    profiler.disable()
    text = io.StringIO()
    stats = pstats.Stats(profiler, stream=text).sort_stats("tottime")
    stats.print_stats(12)
    print(text.getvalue(), file=sys.stderr)
    total = sum(v[2] for v in stats.stats.values()) or 1.0   # type: ignore[attr-defined]
    top = sorted(stats.stats.items(), key=lambda kv: -kv[1][2])[:6]  # type: ignore[attr-defined]
    return {"profile_encode_us": encode * 1e6, "profile_decode_us": decode * 1e6,
            "profile_merge_us": merge * 1e6, "profile_signal_handoff_us": handoff * 1e6,
            "profile_top": "; ".join(f"{Path(k[0]).name}:{k[2]} {100 * v[2] / total:.0f}%"
                                     for k, v in top)}


def build_graph(graph: Any, nodes: int, pong_id: int) -> None:
    fill_graph(graph, nodes)
    deadline = time.monotonic() + 60
    while graph.get_attr(pong_id, "synced") is None:
        if time.monotonic() > deadline:
            raise TimeoutError("bench: echo replica did not receive the 10k graph")
        graph.dispatch(timeout=0.2)


def fill_graph(graph: Any, nodes: int) -> None:
    """The join benchmark's graph: a world node, objects with an RT edge and 3 attributes each,
    and a "marker" node, `nodes` nodes in all (tools/bench/bench_dsr_decode.py decodes the same)."""
    with graph.transaction():
        world = graph.insert_node(WORLD, "world")
    todo = nodes - len(graph) - 1     # exactly `nodes` nodes, marker included
    for chunk in range(0, todo, 1000):
        with graph.transaction():
            for i in range(chunk, min(chunk + 1000, todo)):
                node = graph.insert_node(OBJECT, f"obj{i}", {"x": i * 0.1, "y": 1.0,
                                                               "label": f"thing {i}"})
                graph.insert_or_assign_edge(world.id, node.id, RT,
                                            {"x": i * 0.1, "y": 1.0, "theta": 0.0})
    graph.insert_node(OBJECT, "marker")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--role", choices=["driver", "echo", "join"], default="driver")
    parser.add_argument("--connect", default="")
    parser.add_argument("--graph", default="")
    parser.add_argument("--rounds", type=int, default=1000)
    parser.add_argument("--updates", type=int, default=200_000)
    parser.add_argument("--join-nodes", type=int, default=10_000)
    parser.add_argument("--hold", type=float, default=0.0, help=argparse.SUPPRESS)
    parser.add_argument("--no-poll", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.role == "echo":
        run_echo(args.connect, args.graph, poll=not args.no_poll)
        return 0
    if args.role == "join":
        run_join(args.connect, args.graph, args.hold)
        return 0

    from dsr import SpinPolicy, ZenohSettings, join
    from dsr.process import exit_on_sigterm
    from tools.ports import free_port, port_open
    exit_on_sigterm()
    procs = Procs()
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    graph_name = f"bench{os.getpid()}"
    me = str(Path(__file__).resolve())
    spin = SpinPolicy.from_env()
    result: dict[str, Any] = {"latency_kind": "round_trip", "cpu_count": os.cpu_count(),
                              "dispatch_spin_us": spin.window_us,
                              "dispatch_spin_share_pct": spin.max_share_pct}
    result.update(profile_split())
    try:
        procs.spawn(["-m", "dsr.router", "--listen", endpoint])
        _wait(lambda: port_open(port), 10, "router")
        procs.spawn([me, "--role", "echo", "--connect", endpoint, "--graph", graph_name])
        nopoll_echo = procs.spawn([me, "--role", "echo", "--connect", endpoint, "--graph",
                                   f"{graph_name}np", "--no-poll"])
        settings = ZenohSettings(connect=[endpoint])
        bare = BareZenoh(endpoint, graph_name)
        try:
            with join("driver", graph=graph_name, settings=settings) as graph:
                ping = DsrPing(graph)
                with join("driver", graph=f"{graph_name}np", settings=settings,
                          spin=SpinPolicy(window_us=0)) as nopoll_graph:
                    result.update(latencies(bare, WireFloor(bare.session, graph_name), ping,
                                            DsrPing(nopoll_graph), args.rounds))
                os.killpg(nopoll_echo.pid, signal.SIGTERM)   # the later phases run without them
                result["dsr_over_zenoh_p50"] = result["dsr_p50_ms"] / result["zenoh_p50_ms"]
                result["dsr_nopoll_over_zenoh_p50"] = (result["dsr_nopoll_p50_ms"]
                                                       / result["zenoh_p50_ms"])
                result["dsr_over_zenoh_handoff_p50"] = (result["dsr_p50_ms"]
                                                        / result["zenoh_handoff_p50_ms"])
                result["wire_floor_over_zenoh_p50"] = (result["wire_floor_p50_ms"]
                                                       / result["zenoh_p50_ms"])
                result["dsr_over_wire_floor_p50"] = (result["dsr_p50_ms"]
                                                     / result["wire_floor_p50_ms"])
                result.update(throughput(ping, args.updates))
                build_graph(graph, args.join_nodes, ping.pong_id)
                joins = []
                for k in range(4):       # the first: members encode every element
                    graph.update_node(ping.ping.id, {"joins": k})
                    time.sleep(0.3)
                    joiner = procs.spawn([me, "--role", "join", "--connect", endpoint, "--graph",
                                          graph_name, "--hold", "1.5" if k == 0 else "0"],
                                         stdout=subprocess.PIPE)
                    out, _ = joiner.communicate(timeout=120)
                    joined = json.loads(out.decode().strip().splitlines()[-1])
                    joins.append(joined["join_s"])
                result["join_10k_s"] = sorted(joins[1:])[1]
                result["join_10k_first_s"] = joins[0]
                result["join_nodes"] = joined["nodes"]
                result["join_edges"] = joined["edges"]
                result["join_state_replies"] = joined["state_replies"]
                result["updates_count"] = args.updates
                result["rounds"] = args.rounds
        finally:
            bare.close()
    finally:
        procs.close()
    print(json.dumps({k: (round(v, 4) if isinstance(v, float) else v)
                      for k, v in result.items()}))
    return 0


if __name__ == "__main__":
    sys.exit(main())

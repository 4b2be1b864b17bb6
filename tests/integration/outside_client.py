"""A DSR client written from docs/dsr_wire_format.md and docs/deployment.md alone: it imports
only `zenoh` and the Python standard library (tests/integration/test_outside_client.py checks
that), never chronav.

`python tests/integration/outside_client.py --run RUN_DIR --agent agenda_tool-x --dir D`
(or `--connect E --graph G` for a router without logins)

It joins a run with the run's own `tool` login from `RUN_DIR/connect.json` ("Joining a run"),
subscribes to the deltas, merges every member's state, holds a member token, answers state
queries with its own writes (clock and seen as the doc says) and sends digests; it writes an
`agenda_request` node, tries two writes it may not make (a request created already answered,
which every member's write policy refuses, and a delta on sim_robot's key, which the router's
ACL drops), then deletes its request.  At each step it writes the visible mirror to
`D/<step>.json` and waits for the file `D/<step>.go` before going on, so that the test can
compare the mirror with `chronav dsr dump --json` at quiet moments.
Steps: `joined`, `inserted`, `refused`, `deleted`.
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import secrets
import sys
import threading
import time
from pathlib import Path

import zenoh

FORMAT = "chronav-dsr/1"
ENCODING = "application/json;chronav-dsr/1"
RECEIPT = "~removed"


# ---------------------------------------------------------------- clock ("Clock (HLC)")
class Clock:
    def __init__(self) -> None:
        self.last = 0
        self.lock = threading.Lock()

    def tick(self) -> int:
        with self.lock:
            self.last = max(time.time_ns() // 1_000_000 << 16, self.last + 1)
            return self.last

    def observe(self, stamp: int) -> None:
        with self.lock:
            self.last = max(self.last, stamp)


# ---------------------------------------------------------------- mirror ("Messages")
def json_bytes(value: object) -> bytes:
    text = json.dumps(value, ensure_ascii=False, separators=(",", ":"))
    return text.replace("e-0", "e-").replace("e+0", "e+").encode()


def wins(new: list, old: list | None) -> bool:
    """LWW order: hlc, then replica, then the larger JSON bytes of the value."""
    if old is None:
        return True
    if (new[0], new[1]) != (old[0], old[1]):
        return (new[0], new[1]) > (old[0], old[1])
    return json_bytes(new[2]) > json_bytes(old[2])


class Element:
    def __init__(self) -> None:
        self.add: dict[int, int] = {}
        self.rem: dict[int, int] = {}
        self.cleared = 0
        self.meta: list | None = None
        self.attrs: dict[str, list] = {}

    def merge(self, entry: dict) -> None:
        for field in ("add", "rem"):
            dots = getattr(self, field)
            for replica, stamp in entry.get(field, []):
                dots[replica] = max(dots.get(replica, 0), stamp)
        self.cleared = max(self.cleared, entry.get("cleared", 0))
        if "meta" in entry and wins(entry["meta"][:2] + [entry["meta"][2:]], self._meta_reg()):
            self.meta = entry["meta"]
        for key, register in entry.get("attrs", {}).items():
            if wins(register, self.attrs.get(key)):
                self.attrs[key] = register

    def _meta_reg(self) -> list | None:
        return None if self.meta is None else self.meta[:2] + [self.meta[2:]]

    def present(self) -> bool:
        return any(stamp > self.rem.get(replica, 0) for replica, stamp in self.add.items())

    def entry(self, node_id: int) -> dict:
        """The element as a node entry of a state reply."""
        entry: dict = {"id": node_id, "add": [[r, s] for r, s in self.add.items()],
                       "attrs": dict(self.attrs)}
        if self.rem:
            entry["rem"] = [[r, s] for r, s in self.rem.items()]
        if self.cleared:
            entry["cleared"] = self.cleared
        if self.meta is not None:
            entry["meta"] = self.meta
        return entry

    def visible_attrs(self) -> dict:
        return {k: v[2] for k, v in self.attrs.items()
                if v[0] > self.cleared and k != RECEIPT}


class Mirror:
    def __init__(self) -> None:
        self.nodes: dict[int, Element] = {}
        self.edges: dict[tuple[int, int, str], Element] = {}
        self.lock = threading.Lock()

    def merge(self, message: dict) -> None:
        with self.lock:
            for entry in message.get("nodes", []):
                self.nodes.setdefault(entry["id"], Element()).merge(entry)
            for entry in message.get("edges", []):
                key = (entry["src"], entry["dst"], entry["type"])
                self.edges.setdefault(key, Element()).merge(entry)

    def document(self) -> dict:
        """The visible graph, as `chronav dsr dump --json` prints it ("Visibility")."""
        with self.lock:
            visible = {i: e for i, e in self.nodes.items() if e.present() and e.meta is not None}
            holders: dict[str, list[tuple[int, int]]] = {}
            for node_id, element in visible.items():
                holders.setdefault(element.meta[3], []).append((element.meta[0], node_id))
            winners = {name: min(ids)[1] for name, ids in holders.items()}
            nodes = []
            for node_id in sorted(visible):
                element = visible[node_id]
                name = element.meta[3]
                shown = name if winners[name] == node_id else f"{name}#{node_id}"
                nodes.append({"id": node_id, "type": element.meta[2], "name": shown,
                              "attrs": fix_lists(element.visible_attrs())})
            edges = [{"src": k[0], "dst": k[1], "type": k[2],
                      "attrs": fix_lists(e.visible_attrs())}
                     for k, e in sorted(self.edges.items())
                     if e.present() and k[0] in visible and k[1] in visible]
            return {"nodes": nodes, "edges": edges}


def fix_lists(attrs: dict) -> dict:
    """Lists of numbers are lists of floats."""
    return {k: ([float(x) for x in v] if isinstance(v, list) and not
                (v and isinstance(v[0], str)) else v) for k, v in attrs.items()}


# ---------------------------------------------------------------- the client
def read_run(run_dir: Path) -> tuple[str, str, dict]:
    """endpoint, graph and the `tool` login of a run ("Joining a run")."""
    document = json.loads((run_dir / "connect.json").read_text())
    if document.get("format") != "chronav-run/1":
        raise SystemExit(f"{run_dir}/connect.json: unknown format {document.get('format')!r}")
    return document["endpoint"], document["graph"], document["users"]["tool"]


class Client:
    def __init__(self, endpoint: str, graph: str, agent: str, login: dict | None = None) -> None:
        config = zenoh.Config()
        config.insert_json5("mode", json.dumps("client"))
        config.insert_json5("connect/endpoints", json.dumps([endpoint]))
        config.insert_json5("scouting/multicast/enabled", "false")
        if login is not None:
            config.insert_json5("transport/auth/usrpwd", json.dumps(
                {"user": login["user"], "password": login["password"]}))
        self.session = zenoh.open(config)
        self.graph, self.agent = graph, agent
        self.own: set[int] = set()          # nodes this client wrote: its state reply
        self.replica = secrets.randbelow(2**63 - 2) + 1
        self.clock = Clock()
        self.mirror = Mirror()
        self.inbox: queue.SimpleQueue[bytes] = queue.SimpleQueue()
        self.received = 0
        self.session.declare_subscriber(f"chronav/{graph}/delta/*",
                                        lambda s: self.inbox.put(s.payload.to_bytes()))
        self.send_lock = threading.Lock()     # deltas and digests: one publisher, in order
        self.publisher = self.session.declare_publisher(
            f"chronav/{graph}/delta/{agent}", encoding=ENCODING,
            congestion_control=zenoh.CongestionControl.BLOCK,
            reliability=zenoh.Reliability.RELIABLE)
        self.token = self.session.liveliness().declare_token(f"chronav/{graph}/members/{agent}")
        self.state_key = f"chronav/{graph}/state/{agent}"
        self.queryable = self.session.declare_queryable(self.state_key, self.answer,
                                                        complete=True)
        self.state_replies = 0
        self.stop = threading.Event()
        threading.Thread(target=self.digests, daemon=True).start()

    def answer(self, query: zenoh.Query) -> None:
        """"Writing as a foreign client", state replies: its own writes, `writers`, and
        `clock` / `seen` (everything it stamped up to `clock` is in this reply)."""
        if "stats" in str(query.parameters):
            return                                   # counters are optional: none here
        with self.mirror.lock:
            nodes = [self.mirror.nodes[i].entry(i) for i in sorted(self.own)]
        clock = self.clock.tick()
        message = {"format": FORMAT, "kind": "state", "graph": self.graph, "agent": self.agent,
                   "replica": self.replica, "writers": {str(self.replica): self.agent},
                   "nodes": nodes, "edges": [], "clock": clock,
                   "seen": {str(self.replica): clock}}
        query.reply(self.state_key, json.dumps(message).encode(), encoding=ENCODING)
        self.state_replies += 1

    def digests(self) -> None:
        """"Digests and anti-entropy": every 0.5 s, after the deltas it describes."""
        while not self.stop.wait(0.5):
            clock = self.clock.tick()
            message = {"format": FORMAT, "kind": "digest", "graph": self.graph,
                       "agent": self.agent, "replica": self.replica, "clock": clock,
                       "seen": {str(self.replica): clock}}
            try:
                with self.send_lock:
                    self.publisher.put(json.dumps(message).encode())
            except zenoh.ZError:
                return

    def accept(self, message: dict) -> None:
        stamps = [message.get("clock", 0)]
        for entry in message.get("nodes", []) + message.get("edges", []):
            stamps += [s for _, s in entry.get("add", [])] + [entry.get("cleared", 0)]
            stamps += [r[0] for r in entry.get("attrs", {}).values()]
        self.clock.observe(max(stamps))
        if message["kind"] in ("delta", "state"):      # digests describe, they carry no writes
            self.mirror.merge(message)

    def sync(self) -> int:
        replies = self.session.get(f"chronav/{self.graph}/state/*",
                                   target=zenoh.QueryTarget.ALL,
                                   consolidation=zenoh.ConsolidationMode.NONE, timeout=10)
        count = 0
        for reply in replies:
            if reply.ok is not None:
                self.accept(json.loads(reply.ok.payload.to_bytes()))
                count += 1
        return count

    def drain(self, quiet_s: float = 0.6) -> None:
        """Merge deltas until none arrived for `quiet_s` (digests keep coming: not counted)."""
        last = time.monotonic()
        while time.monotonic() - last < quiet_s:
            try:
                payload = self.inbox.get(timeout=quiet_s)
            except queue.Empty:
                return
            message = json.loads(payload)
            if message.get("agent") != self.agent:
                self.accept(message)
                if message["kind"] == "delta":
                    self.received += 1
                    last = time.monotonic()

    def put(self, nodes: list[dict], keep: bool = True) -> None:
        message = {"format": FORMAT, "kind": "delta", "graph": self.graph, "agent": self.agent,
                   "replica": self.replica, "nodes": nodes, "edges": []}
        if keep:
            self.mirror.merge(message)
            self.own.update(entry["id"] for entry in nodes)
        with self.send_lock:
            self.publisher.put(json.dumps(message).encode())

    def insert(self, node_id: int, type_: str, name: str, attrs: dict, keep: bool = True) -> None:
        t = self.clock.tick()
        me = self.replica
        self.put([{"id": node_id, "add": [[me, t]], "meta": [t, me, type_, name],
                   "attrs": {k: [t, me, v] for k, v in attrs.items()}}], keep)

    def put_as(self, agent: str, nodes: list[dict]) -> None:
        """A delta on another agent's key: the router's ACL drops it (not kept here)."""
        message = {"format": FORMAT, "kind": "delta", "graph": self.graph, "agent": agent,
                   "replica": self.replica, "nodes": nodes, "edges": []}
        self.session.put(f"chronav/{self.graph}/delta/{agent}", json.dumps(message).encode(),
                         encoding=ENCODING, allowed_destination=zenoh.Locality.REMOTE)

    def delete(self, node_id: int) -> None:
        t = self.clock.tick()
        with self.mirror.lock:
            adds = [[r, s] for r, s in self.mirror.nodes[node_id].add.items()]
        self.put([{"id": node_id, "rem": adds, "cleared": t,
                   "attrs": {RECEIPT: [t, self.replica, True]}}])

    def close(self) -> None:
        self.stop.set()
        self.session.close()


def checkpoint(directory: Path, step: str, client: Client) -> None:
    client.drain()
    document = {"step": step, "received": client.received, **client.mirror.document()}
    tmp = directory / f"{step}.tmp"
    tmp.write_text(json.dumps(document))
    os.replace(tmp, directory / f"{step}.json")
    go = directory / f"{step}.go"
    deadline = time.monotonic() + 120
    while not go.exists():
        if time.monotonic() > deadline:
            raise TimeoutError(f"no {go}")
        client.drain(0.05)


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--run", type=Path, help="run directory (its connect.json)")
    parser.add_argument("--connect")
    parser.add_argument("--graph", default="chronav")
    parser.add_argument("--agent", required=True)
    parser.add_argument("--dir", required=True, type=Path)
    args = parser.parse_args()
    if args.run is not None:
        endpoint, graph, login = read_run(args.run)
        client = Client(endpoint, graph, args.agent, login)
    else:
        client = Client(args.connect, args.graph, args.agent)
    try:
        client.sync()
        checkpoint(args.dir, "joined", client)
        node_id = (secrets.randbelow(2**31 - 1) + 1) << 32 | 1
        client.insert(node_id, "agenda_request", f"agenda_request/{node_id}",
                      {"change": json.dumps({"op": "cancel", "id": "nothing"}),
                       "state": "pending", "requested_by": "outside client",
                       "requested_s": 36000.0})
        checkpoint(args.dir, "inserted", client)
        # refused: created already answered (write policy), and written as sim_robot (ACL)
        forged = node_id + 1
        client.insert(forged, "agenda_request", f"agenda_request/{forged}",
                      {"change": "{}", "state": "accepted"}, keep=False)
        t = client.clock.tick()
        client.put_as("sim_robot", [{"id": node_id, "attrs": {"state": [t, client.replica,
                                                                         "accepted"]}}])
        checkpoint(args.dir, "refused", client)
        client.delete(node_id)
        checkpoint(args.dir, "deleted", client)
    finally:
        client.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())

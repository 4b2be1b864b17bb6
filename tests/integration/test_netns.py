"""DSR replication across a real network boundary, partition and heal (Linux network namespaces).

Two namespaces joined by a veth pair stand for two hosts: the router and replica `a1` live in A,
replicas `b1` and `b2` in B and reach the router over the veth (10.x addresses that exist only
inside these namespaces).  All three keep writing while the link is cut for longer than the
lease, then the link comes back.  "Acknowledged" write = applied to its writer's local replica
(what an agent sees when its write call returns).  After the heal every replica must hold every
acknowledged write of every writer, within a bounded time, and all digests must agree.

Needs root and `ip netns` (skipped with the reason otherwise).  Namespaces get unique names per
run and are deleted in `finally`, also when the test fails.
"""

from __future__ import annotations

import os
import secrets
import shutil
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.integration.fault_support import holds_all_writes, spawn_script, status_of
from tests.support import free_port, wait_until

pytestmark = [pytest.mark.netns, pytest.mark.slow]

LEASE_MS = 1000
PARTITION_S = 3.0
HEAL_BOUND_S = 15.0       # client reconnect backoff (<= 4 s) + anti-entropy, with margin
ENV = {"CHRONAV_ZENOH_LEASE_MS": str(LEASE_MS), "CHRONAV_WRITE_POLICY": "allow-all"}
#: `python -c EXEC ip netns exec NS python ...`: `ip netns exec` execs in place, so the pid the
#: process group fixture kills is the replica's own
EXEC = "import os, sys; os.execvp(sys.argv[1], sys.argv[1:])"


def ip(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["ip", *args], capture_output=True, text=True, timeout=10, check=False)


def netns_unavailable() -> str | None:
    if sys.platform != "linux" or shutil.which("ip") is None:
        return "needs Linux with iproute2 (`ip`)"
    probe = f"chronav-probe-{secrets.token_hex(3)}"
    result = ip("netns", "add", probe)
    if result.returncode != 0:
        return f"`ip netns add` is not permitted here: {result.stderr.strip()}"
    ip("netns", "del", probe)
    return None


@dataclass(frozen=True)
class Link:
    ns_a: str
    ns_b: str
    dev_a: str
    dev_b: str
    addr_a: str
    addr_b: str

    def prefix(self, ns: str) -> list[str]:
        return ["-c", EXEC, "ip", "netns", "exec", ns, sys.executable]

    def set_b(self, state: str) -> None:
        result = ip("-n", self.ns_b, "link", "set", self.dev_b, state)
        assert result.returncode == 0, result.stderr


@contextmanager
def two_hosts() -> Iterator[Link]:
    tag = f"{os.getpid() % 4096:03x}{secrets.token_hex(2)}"
    subnet = f"10.{secrets.randbelow(50) + 200}.{secrets.randbelow(256)}"
    link = Link(f"chronav-a-{tag}", f"chronav-b-{tag}", f"cv{tag}a", f"cv{tag}b",
                f"{subnet}.1", f"{subnet}.2")
    try:
        steps = [("netns", "add", link.ns_a), ("netns", "add", link.ns_b),
                 ("link", "add", link.dev_a, "type", "veth", "peer", "name", link.dev_b),
                 ("link", "set", link.dev_a, "netns", link.ns_a),
                 ("link", "set", link.dev_b, "netns", link.ns_b)]
        for ns, dev, addr in ((link.ns_a, link.dev_a, link.addr_a),
                              (link.ns_b, link.dev_b, link.addr_b)):
            steps += [("-n", ns, "addr", "add", f"{addr}/24", "dev", dev),
                      ("-n", ns, "link", "set", dev, "up"), ("-n", ns, "link", "set", "lo", "up")]
        for step in steps:
            result = ip(*step)
            assert result.returncode == 0, f"ip {' '.join(step)}: {result.stderr}"
        yield link
    finally:
        for ns in (link.ns_a, link.ns_b):
            ip("netns", "del", ns)              # also removes the veth end inside it
        ip("link", "del", link.dev_a)           # if setup failed before the move


def wait_router(log: Path, proc: object, timeout: float = 15.0) -> None:
    def ready() -> bool:
        text = log.read_text() if log.exists() else ""
        return "dsr.router ready" in text or proc.poll() is not None  # type: ignore[attr-defined]
    wait_until(ready, timeout, message="router ready in namespace A")
    assert proc.poll() is None, log.read_text()  # type: ignore[attr-defined]


def reachable_from_host(address: str, port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.settimeout(0.5)
        return sock.connect_ex((address, port)) == 0


def acked(paths: dict[str, Path]) -> dict[str, int]:
    return {name: int(status_of(path).get("acked", 0)) for name, path in paths.items()}


def test_replication_crosses_namespaces_survives_partition_and_converges(procs, tmp_path):
    reason = netns_unavailable()
    if reason is not None:
        pytest.skip(reason)
    with two_hosts() as link:
        port, local_port = free_port(), free_port()
        router_log = tmp_path / "router.log"
        router = procs.spawn([*link.prefix(link.ns_a), "-m", "dsr.router",
                              "--listen", f"tcp/{link.addr_a}:{port}",
                              "--listen", f"tcp/127.0.0.1:{local_port}",
                              "--lease-ms", str(LEASE_MS)], log_path=router_log)
        wait_router(router_log, router)
        assert not reachable_from_host(link.addr_a, port), "the namespace boundary leaks"

        writes = 700                      # 7 s at 100 writes/s per writer
        common = ("--writes", str(writes), "--period-ms", "10")
        paths = {}
        for agent, ns, endpoint in (("a1", link.ns_a, f"tcp/127.0.0.1:{local_port}"),
                                    ("b1", link.ns_b, f"tcp/{link.addr_a}:{port}"),
                                    ("b2", link.ns_b, f"tcp/{link.addr_a}:{port}")):
            _, paths[agent] = spawn_script(procs, tmp_path, agent, *common, connect=endpoint,
                                           env=ENV, prefix=link.prefix(ns))

        def sees(viewer: str, writer: str, at_least: int) -> bool:
            counter = (status_of(paths[viewer]).get("counters") or {}).get(f"{writer}-counter")
            return counter is not None and counter >= at_least
        wait_until(lambda: sees("a1", "b1", 20) and sees("b2", "a1", 20), 30,
                   message="replication across the veth in both directions")

        link.set_b("down")
        cut_at = time.monotonic()
        try:
            time.sleep(0.5 + LEASE_MS / 1000)
            frozen_view = (status_of(paths["a1"]).get("counters") or {}).get("b1-counter")
            before = acked(paths)
            time.sleep(max(0.0, PARTITION_S - (time.monotonic() - cut_at)))
            during = acked(paths)
            isolated_view = (status_of(paths["a1"]).get("counters") or {}).get("b1-counter")
        finally:
            link.set_b("up")
        healed_at = time.monotonic()
        acked_at_heal = acked(paths)
        assert all(during[n] > before[n] for n in paths), f"a side stopped writing: {during}"
        assert isolated_view == frozen_view, "A kept seeing B's writes: the link was not cut"

        wait_until(lambda: all(holds_all_writes(status_of(p), acked_at_heal)
                               for p in paths.values()), HEAL_BOUND_S,
                   message="every replica holding every write acknowledged before the heal")
        catch_up_s = time.monotonic() - healed_at

        wait_until(lambda: all(status_of(p).get("done") for p in paths.values()), 30,
                   message="writers finished")
        final = acked(paths)
        assert final == dict.fromkeys(paths, writes)
        wait_until(lambda: len({status_of(p).get("digest") for p in paths.values()}) == 1
                   and all(holds_all_writes(status_of(p), final) for p in paths.values()),
                   HEAL_BOUND_S, message="final convergence with no acknowledged write lost")
        converged_s = time.monotonic() - healed_at
        print(f"partition {PARTITION_S:.0f} s (lease {LEASE_MS} ms): catch-up {catch_up_s:.2f} s "
              f"after heal, final convergence {converged_s:.2f} s after heal")
        for path in paths.values():
            stats = status_of(path)["stats"]
            assert stats["errors"] == 0 and stats["rejected"] == 0, stats

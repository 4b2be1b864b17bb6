"""Acceptance tests of DSR replication with separate OS processes over a real Zenoh router."""

from __future__ import annotations

import signal

import orjson
import pytest
import zenoh

from dsr import DSRGraph, ZenohSettings, join, wire
from dsr.collector import GC_THRESHOLDS
from dsr.policy import DenyTypes
from tests.integration.dsr_support import (converged, read_status, spawn_worker, start_router)
from tests.support import wait_until

pytestmark = pytest.mark.slow


def test_three_concurrent_writers_converge(procs, tmp_path):
    endpoint, _ = start_router(procs, tmp_path)
    paths = []
    for index, agent in enumerate(("a", "b", "c")):
        _, path = spawn_worker(procs, endpoint, tmp_path, agent, "--ops", "150",
                               "--seed", str(index))
        paths.append(path)
    wait_until(lambda: converged(paths), 60, message="three replicas converged")
    statuses = [read_status(p) for p in paths]
    done: dict[str, int] = {}
    for status in statuses:
        assert status["stats"]["rejected"] == 0 and status["stats"]["errors"] == 0, \
            {key: status["stats"].get(key) for key in ("rejects", "last_reject", "errors")}
        for kind, count in status["ops"].items():
            done[kind] = done.get(kind, 0) + count
        # a process holding a replica runs the cyclic collector less often (dsr/collector.py)
        assert status["gc_threshold"][0] >= GC_THRESHOLDS[0], status["gc_threshold"]
    for kind in ("insert_node", "update_node", "delete_node", "insert_edge", "delete_edge"):
        assert done.get(kind, 0) > 0, done
    assert statuses[0]["nodes"] > 10
    assert {n.split("-")[0] for n in statuses[0]["names"]} >= {"a", "b", "c"}


def test_sigkilled_replica_rejoins_and_converges(procs, tmp_path):
    endpoint, _ = start_router(procs, tmp_path)
    proc_a, path_a = spawn_worker(procs, endpoint, tmp_path, "a", "--ops", "200", "--seed", "1")
    proc_b, path_b = spawn_worker(procs, endpoint, tmp_path, "b", "--ops", "1000000",
                                  "--seed", "2")

    def a_sees_b() -> bool:
        status = read_status(path_a)
        return status is not None and sum(n.startswith("b-") for n in status["names"]) >= 10
    wait_until(a_sees_b, 30, message="a receiving b's writes")
    procs.kill(proc_b, signal.SIGKILL)
    assert proc_b.returncode == -signal.SIGKILL
    proc_b2, path_b2 = spawn_worker(procs, endpoint, tmp_path, "b", "--ops", "40", "--seed", "3")
    wait_until(lambda: converged([path_a, path_b2]), 60, message="a and restarted b converged")
    assert proc_a.poll() is None and proc_b2.poll() is None
    names = read_status(path_b2)["names"]
    assert sum(n.startswith("b-") for n in names) >= 10   # the dead incarnation's nodes
    assert sum(n.startswith("a-") for n in names) > 0


def test_late_joiner_receives_the_whole_graph(procs, tmp_path):
    endpoint, _ = start_router(procs, tmp_path)
    _, path_a = spawn_worker(procs, endpoint, tmp_path, "a", "--world", "2000", "--ops", "20")
    wait_until(lambda: (read_status(path_a) or {}).get("done", False), 30, message="a's world")
    _, path_c = spawn_worker(procs, endpoint, tmp_path, "c")
    wait_until(lambda: converged([path_a, path_c]), 30, message="late joiner converged")
    assert read_status(path_c)["nodes"] >= 2000


def _client(endpoint: str) -> zenoh.Session:
    return zenoh.open(ZenohSettings(connect=[endpoint]).to_zenoh_config())


def test_malformed_payloads_are_rejected_and_counted(procs, tmp_path):
    endpoint, _ = start_router(procs, tmp_path)
    proc_a, path_a = spawn_worker(procs, endpoint, tmp_path, "a", "--world", "20")
    wait_until(lambda: (read_status(path_a) or {}).get("done", False), 30, message="a ready")
    before = read_status(path_a)["digest"]

    mallory = DSRGraph("mallory", graph="chronav", replica_id=424242)
    sent: list[bytes] = []
    mallory.attach(sent.append)
    mallory.insert_node("object", "m1", {"v": 1})
    good = orjson.loads(sent[0])

    def variant(**over):
        return orjson.dumps({**good, **over})
    node = good["nodes"][0]
    bad_payloads = {
        "mallory": [b"\x00\x01garbage\xff", b'{"hello": "world"}', variant(kind="state"),
                    variant(agent="a"),                                   # forged writer
                    variant(nodes=[{**node, "add": [[777, node["add"][0][1]]]}]),
                    variant(nodes=[{**node, "meta": [2**62, 424242, "object", "m9"]}])],
        "a": [sent[0]],                     # mallory's delta published on a's key
    }
    session = _client(endpoint)
    try:
        # Queryable first: a replica asks a new member for its state as soon as its token appears.
        queryable = session.declare_queryable(
            "chronav/chronav/state/eve", lambda q: q.reply(q.key_expr, b"not json"))
        token = session.liveliness().declare_token("chronav/chronav/members/eve")
        for agent, payloads in bad_payloads.items():
            for payload in payloads:
                session.put(wire.delta_key("chronav", agent), payload)

        def rejected() -> int:
            return (read_status(path_a) or {"stats": {"rejected": -1}})["stats"]["rejected"]
        wait_until(lambda: rejected() >= 8, 20, message="8 rejections (7 deltas + 1 state)")
        status = read_status(path_a)
        assert status["digest"] == before and status["stats"]["errors"] == 0
        assert proc_a.poll() is None
        session.put(wire.delta_key("chronav", "mallory"), sent[0])   # the valid one still works
        wait_until(lambda: "m1" in (read_status(path_a) or {"names": []})["names"], 20,
                   message="valid delta applied")
        assert read_status(path_a)["stats"]["rejected"] == 8
        queryable.undeclare()
        token.undeclare()
    finally:
        session.close()


def test_writes_during_router_outage_reach_the_others(procs, tmp_path):
    endpoint, router = start_router(procs, tmp_path)
    _, path_a = spawn_worker(procs, endpoint, tmp_path, "a", "--world", "5")
    wait_until(lambda: (read_status(path_a) or {}).get("done", False), 30, message="a ready")
    with join("t", graph="chronav", settings=ZenohSettings(connect=[endpoint])) as graph:
        assert len(graph) == 5
        procs.kill(router, signal.SIGKILL)
        for i in range(5):
            graph.insert_node("object", f"offline-{i}")      # puts vanish: no router
        port = int(endpoint.rsplit(":", 1)[1])
        start_router(procs, tmp_path, port=port)
        wait_until(lambda: "offline-4" in (read_status(path_a) or {"names": []})["names"], 30,
                   message="anti-entropy after reconnect")
        wait_until(lambda: read_status(path_a)["digest"] == graph.digest(), 10,
                   message="same graph after reconnect")


def test_write_policy_drops_refused_deltas(procs, tmp_path):
    endpoint, _ = start_router(procs, tmp_path)
    settings = ZenohSettings(connect=[endpoint])
    policy = DenyTypes({"robot"}, agents={"rogue"})
    with join("guard", settings=settings, policy=policy) as guard, \
            join("rogue", settings=settings) as rogue:
        rogue.insert_node("robot", "r2d2")
        rogue.insert_node("person", "bob")
        wait_until(lambda: guard.get_node_by_name("bob") is not None, 10, message="bob")
        assert guard.get_node_by_name("r2d2") is None
        # rogue's state, fetched after its writes (as the fetch raised by its token is on a
        # loaded machine): it must not bring back the refused node either
        guard.replica.sync("rogue")
        assert guard.get_node_by_name("r2d2") is None
        stats = guard.replica.stats
        # the delta, and the robot part of each state of rogue's fetched after its writes
        assert stats.rejected_policy >= 2 and stats.rejected == 0
        assert stats.rejects == {"policy": stats.rejected_policy}


def test_members_delta_keys_are_declared_while_they_run(procs, tmp_path):
    """Each replica declares the exact delta key of every running member in its session (a
    faster delivery than through the wildcard subscription alone, Replica._declare_writer_key)
    and undeclares it when the member leaves; deltas flow the same either way."""
    endpoint, _ = start_router(procs, tmp_path)
    settings = ZenohSettings(connect=[endpoint])
    with join("first", settings=settings) as first:
        with join("second", settings=settings) as second:
            leaver = second.replica
            # the joiner declares from the member list, the first from the liveliness token
            assert set(second.replica._writer_keys) == {"first"}
            wait_until(lambda: set(first.replica._writer_keys) == {"second"}, 10,
                       message="first declares second's delta key")
            assert str(first.replica._writer_keys["second"]) == wire.delta_key("chronav",
                                                                                "second")
            node = second.insert_node("person", "ana", {"x": 1.0})
            second.update_node(node.id, {"x": 2.0})
            wait_until(lambda: node.id in first and first.get_attr(node.id, "x") == 2.0, 10,
                       message="second's deltas reach first")
        wait_until(lambda: not first.replica._writer_keys, 10,
                   message="second's key undeclared after it left")
        assert leaver._writer_keys == {}              # closed: everything undeclared
        again = first.insert_node("person", "bo")
        assert first.get_node(again.id) is not None

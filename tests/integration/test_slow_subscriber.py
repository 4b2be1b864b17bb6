"""A stalled replica (SIGSTOP) must not slow the others down, and must catch up afterwards.

Three processes on one router: a writer at a fixed loop rate, an observer, and a replica that is
frozen for a few seconds (longer than the link lease).  Zenoh expires the frozen member's
session, so the writer's BLOCK publications are not held back by it; after SIGCONT the frozen
replica reconnects and recovers the deltas it missed by state transfer.
"""

from __future__ import annotations

import os
import signal
import time

import pytest

from tests.integration.dsr_support import start_router
from tests.integration.fault_support import holds_all_writes, rate, spawn_script, status_of
from tests.support import wait_until

pytestmark = pytest.mark.slow

LEASE_MS = 1000
STALL_S = 3.0
PERIOD_MS = 5.0           # 200 writes/s, a busy agent loop
ENV = {"CHRONAV_ZENOH_LEASE_MS": str(LEASE_MS), "CHRONAV_WRITE_POLICY": "allow-all"}


def test_stalled_subscriber_neither_slows_others_nor_stays_behind(procs, tmp_path):
    endpoint, _ = start_router(procs, tmp_path)
    slow, slow_st = spawn_script(procs, tmp_path, "slow", connect=endpoint, env=ENV)
    _, obs_st = spawn_script(procs, tmp_path, "observer", connect=endpoint, env=ENV)
    wait_until(lambda: status_of(slow_st).get("script_done") and status_of(obs_st).get("script_done"),
               20, message="slow and observer joined")
    writes = 1000       # 5 s at 200/s: 1.5 s before the stall, 3 s of stall, the rest after
    _, writer_st = spawn_script(procs, tmp_path, "writer", "--writes", str(writes),
                                "--period-ms", str(PERIOD_MS), "--measure", connect=endpoint,
                                env=ENV)
    wait_until(lambda: status_of(obs_st).get("stats", {}).get("received", 0) > 100, 20,
               message="observer receiving the writer")
    time.sleep(1.0)
    merged_before = status_of(slow_st)["stats"]["state_merged"]
    frozen_at = time.time()
    os.kill(slow.pid, signal.SIGSTOP)
    try:
        time.sleep(STALL_S)
        acked_at_thaw = status_of(writer_st)["acked"]
    finally:
        thawed_at = time.time()
        os.kill(slow.pid, signal.SIGCONT)
    wait_until(lambda: holds_all_writes(status_of(slow_st), {"writer": acked_at_thaw}), 20,
               message="the thawed replica holding every write made while it was frozen")
    catch_up_s = time.time() - thawed_at

    writer = status_of(writer_st)
    before = rate(writer["history"], frozen_at - 1.0, frozen_at)
    during = rate(writer["history"], frozen_at, thawed_at)
    seen_before = rate(status_of(obs_st)["history"], frozen_at - 1.0, frozen_at, column=2)
    seen_during = rate(status_of(obs_st)["history"], frozen_at, thawed_at, column=2)
    print(f"writer {before:.0f} -> {during:.0f} writes/s, observer {seen_before:.0f} -> "
          f"{seen_during:.0f} deltas/s during a {STALL_S:.0f} s stall; catch-up {catch_up_s:.2f} s")
    assert before > 100, "the writer did not reach its loop rate before the stall"
    assert during >= 0.6 * before, f"writer rate collapsed: {before:.0f} -> {during:.0f}/s"
    assert seen_during >= 0.6 * seen_before, f"observer starved: {seen_before:.0f} -> {seen_during:.0f}"

    wait_until(lambda: status_of(writer_st).get("done"), 30, message="writer finished")
    final = status_of(writer_st)["acked"]
    assert final == writes
    wait_until(lambda: all(status_of(p).get("digest") == status_of(writer_st).get("digest")
                           for p in (slow_st, obs_st)), 20, message="all three converged")
    slow_status = status_of(slow_st)
    assert holds_all_writes(slow_status, {"writer": final})
    # Frozen deltas were lost to it and came back by state transfer, not by replay.
    assert slow_status["stats"]["state_merged"] > merged_before
    assert slow_status["stats"]["received"] < writes
    assert slow_status["stats"]["errors"] == 0 and slow.poll() is None

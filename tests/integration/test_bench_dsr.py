"""tools/bench/bench_dsr.py runs end to end (router, echo and joiner processes on a free loopback port)
and prints one flat JSON object holding every key the issue's goals are read from, the
wire-floor split and the same round trip without dispatch() polling.  No speed is asserted: the goals are checked by running the benchmark."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from tests.support import REPO_ROOT


def test_small_run_prints_every_goal_key() -> None:
    result = subprocess.run(
        [sys.executable, "tools/bench/bench_dsr.py", "--rounds", "100", "--updates", "3000",
         "--join-nodes", "600"],
        cwd=REPO_ROOT, capture_output=True, text=True, timeout=240, check=True)
    lines = result.stdout.strip().splitlines()
    assert len(lines) == 1, result.stdout
    values = json.loads(lines[0])
    for key in ("dsr_p50_ms", "zenoh_p50_ms", "dsr_over_zenoh_p50", "updates_per_s",
                "join_10k_s", "wire_floor_p50_ms", "wire_floor_over_zenoh_p50",
                "dsr_over_wire_floor_p50", "profile_encode_us", "profile_decode_us",
                "profile_merge_us", "profile_signal_handoff_us", "dsr_nopoll_p50_ms",
                "dsr_nopoll_over_zenoh_p50"):
        assert values[key] > 0, key
    assert values["dispatch_spin_us"] == 1000 and values["dispatch_spin_share_pct"] == 25
    assert 0 <= values["dispatch_poll_core_share"] < 1.0
    assert values["dispatch_poll_hits"] >= 0 and values["dispatch_poll_misses"] >= 0
    assert values["dispatch_received_by_agent"] >= 0
    assert values["dsr_nopoll_received_by_agent"] == 0, "a replica that never polls never takes"
    ratio = values["dsr_p50_ms"] / values["zenoh_p50_ms"]      # printed rounded to 4 digits
    assert values["dsr_over_zenoh_p50"] == pytest.approx(ratio, rel=1e-3)
    ratio = values["dsr_p50_ms"] / values["wire_floor_p50_ms"]
    assert values["dsr_over_wire_floor_p50"] == pytest.approx(ratio, rel=1e-3)
    assert values["join_nodes"] >= 600 and values["updates_count"] == 3000
    assert all(not isinstance(v, (dict, list)) for v in values.values())

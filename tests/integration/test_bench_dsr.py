"""tools/bench_dsr.py runs end to end (router, echo and joiner processes on a free loopback port)
and prints one flat JSON object holding every key the issue's goals are read from, and the
wire-floor split.  No speed is asserted: the goals are checked by running the benchmark."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from tests.support import REPO_ROOT


def test_small_run_prints_every_goal_key() -> None:
    result = subprocess.run(
        [sys.executable, "tools/bench_dsr.py", "--rounds", "100", "--updates", "3000",
         "--join-nodes", "600"],
        cwd=REPO_ROOT, capture_output=True, text=True, timeout=240, check=True)
    lines = result.stdout.strip().splitlines()
    assert len(lines) == 1, result.stdout
    values = json.loads(lines[0])
    for key in ("dsr_p50_ms", "zenoh_p50_ms", "dsr_over_zenoh_p50", "updates_per_s",
                "join_10k_s", "wire_floor_p50_ms", "wire_floor_over_zenoh_p50",
                "dsr_over_wire_floor_p50", "profile_encode_us", "profile_decode_us",
                "profile_merge_us", "profile_signal_handoff_us"):
        assert values[key] > 0, key
    ratio = values["dsr_p50_ms"] / values["zenoh_p50_ms"]      # printed rounded to 4 digits
    assert values["dsr_over_zenoh_p50"] == pytest.approx(ratio, rel=1e-3)
    ratio = values["dsr_p50_ms"] / values["wire_floor_p50_ms"]
    assert values["dsr_over_wire_floor_p50"] == pytest.approx(ratio, rel=1e-3)
    assert values["join_nodes"] >= 600 and values["updates_count"] == 3000
    assert all(not isinstance(v, (dict, list)) for v in values.values())

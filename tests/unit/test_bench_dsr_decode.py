"""tools/bench/bench_dsr_decode.py prints one flat JSON object of the receive path's costs.

Run as a user runs it, in its own process (in the test process its collections would walk the
whole suite's heap: 5 s instead of 1)."""

from __future__ import annotations

import json
import subprocess
import sys

from tests.support import REPO_ROOT


def test_prints_one_flat_json_object() -> None:
    result = subprocess.run([sys.executable, "tools/bench/bench_dsr_decode.py", "--nodes", "300", "--repeat", "1"],
                            cwd=REPO_ROOT, capture_output=True, text=True, timeout=120, check=True)
    lines = result.stdout.strip().splitlines()
    assert len(lines) == 1
    values = json.loads(lines[0])
    assert values["nodes"] == 300 and values["state_parts"] >= 1
    for key in ("decode_10k_ms", "parse_10k_orjson_ms", "merge_10k_ms",
                "decode_update_us", "parse_update_orjson_us"):
        assert values[key] > 0, key

"""tools/bench_dsr_decode.py prints one flat JSON object of the receive path's costs."""

from __future__ import annotations

import json

from tools import bench_dsr_decode


def test_prints_one_flat_json_object(capsys):
    assert bench_dsr_decode.main(["--nodes", "300", "--repeat", "1"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 1
    result = json.loads(lines[0])
    assert result["nodes"] == 300 and result["state_parts"] >= 1
    for key in ("decode_10k_ms", "parse_10k_orjson_ms", "merge_10k_ms",
                "decode_update_us", "parse_update_orjson_us"):
        assert result[key] > 0, key

"""Run `chronav ... --json` as a user would, in its own process group, and parse its result."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

import pytest

from tests.support import ProcessGroup


def run_json(args: list[str], log: Path, timeout_s: float) -> dict[str, Any]:
    """`python -m tools.cli ARGS --json --timeout T`: the last JSON line of its output, plus its exit code.

    The run goes under ``recordings/`` next to the log (``CHRONAV_RUNS``), not into the source tree."""
    group = ProcessGroup()
    try:
        proc = group.spawn(["-m", "tools.cli", *args, "--json", "--timeout", str(timeout_s - 30)],
                           env={"RERUN": "on", "CHRONAV_RUNS": str(log.parent / "recordings")}, log_path=log)
        try:
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            pytest.fail(f"`chronav {' '.join(args)}` did not finish; log:\n{log.read_text()[-3000:]}")
    finally:
        group.close()
    text = log.read_text()
    line = next((ln for ln in reversed(text.splitlines()) if ln.startswith("{")), None)
    assert line is not None, f"no JSON result; log:\n{text[-3000:]}"
    result = json.loads(line)
    result["returncode"] = proc.returncode
    return result


def launch_json(scene: str, log: Path, timeout_s: float = 300, extra: list[str] | None = None) -> dict[str, Any]:
    return run_json(["launch", scene, *(extra or [])], log, timeout_s)

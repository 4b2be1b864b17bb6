"""Run `chronav launch SCENE --json` as a user would, in its own process group, and parse its result."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from tests.support import ProcessGroup


def launch_json(scene: str, log: Path, timeout_s: float = 300, extra: list[str] | None = None) -> dict:
    group = ProcessGroup()
    try:
        proc = group.spawn(["-m", "tools.cli", "launch", scene, "--json", "--timeout", str(timeout_s - 30),
                            *(extra or [])], env={"RERUN": "on"}, log_path=log)
        try:
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            pytest.fail(f"launch of {scene} did not finish; log:\n{log.read_text()[-3000:]}")
    finally:
        group.close()
    text = log.read_text()
    line = next((ln for ln in reversed(text.splitlines()) if ln.startswith("{")), None)
    assert line is not None, f"no JSON result; log:\n{text[-3000:]}"
    result = json.loads(line)
    result["returncode"] = proc.returncode
    return result

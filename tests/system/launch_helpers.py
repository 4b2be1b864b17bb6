"""Run `chronav ... --json` as a user would, in its own process group, and parse its result.

One way for every system test to start a run: ``run_json``/``launch_json`` for one command that
the test waits for, and the ``evaluate_runs`` fixture for `chronav evaluate` sweeps started in the
background together (tests/system/test_evaluate.py, test_parity.py), each with its log beside its
output folder, every process killed when the module ends.
"""

from __future__ import annotations

import json
import subprocess
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from tests.support import ProcessGroup, process_group


def _wait_for_json(proc: subprocess.Popen[bytes], log: Path, timeout_s: float, what: str) -> dict[str, Any]:
    """Wait for ``proc``; the last JSON line of its log, plus its exit code (``returncode``)."""
    try:
        proc.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        pytest.fail(f"`{what}` did not finish; log:\n{log.read_text()[-3000:]}")
    text = log.read_text()
    line = next((ln for ln in reversed(text.splitlines()) if ln.startswith("{")), None)
    assert line is not None, f"no JSON result; log:\n{text[-3000:]}"
    return {**json.loads(line), "returncode": proc.returncode}


def run_json(args: list[str], log: Path, timeout_s: float) -> dict[str, Any]:
    """`python -m tools.cli ARGS --json --timeout T`: the last JSON line of its output, plus its exit code.

    The run goes under ``recordings/`` next to the log (``CHRONAV_RUNS``), not into the source tree."""
    group = ProcessGroup()
    try:
        proc = group.spawn(["-m", "tools.cli", *args, "--json", "--timeout", str(timeout_s - 30)],
                           env={"RERUN": "on", "CHRONAV_RUNS": str(log.parent / "recordings")}, log_path=log)
        return _wait_for_json(proc, log, timeout_s, f"chronav {' '.join(args)}")
    finally:
        group.close()


def launch_json(scene: str, log: Path, timeout_s: float = 300, extra: list[str] | None = None) -> dict[str, Any]:
    return run_json(["launch", scene, *(extra or [])], log, timeout_s)


@dataclass
class Sweep:
    """A `chronav evaluate` under way: its process and its log (``<out>.log`` beside ``out``)."""

    proc: subprocess.Popen[bytes]
    log: Path


class EvaluateRuns:
    """Starts `chronav evaluate SCENE --planners P --seeds 1 --out OUT --timeout T --json EXTRA...`
    in the background (several at once: their agents interleave as load decides) and waits for
    their results."""

    def __init__(self, group: ProcessGroup) -> None:
        self.group = group

    def start(self, scene: Path, out: Path, planners: str, *extra: str, run_timeout_s: float = 300,
              env: dict[str, str] | None = None) -> Sweep:
        log = out.parent / f"{out.name}.log"
        proc = self.group.spawn(["-m", "tools.cli", "evaluate", str(scene), "--planners", planners, "--seeds", "1",
                                 "--out", str(out), "--timeout", str(run_timeout_s), "--json", *extra],
                                env=env, log_path=log)
        return Sweep(proc, log)

    def result(self, sweep: Sweep, timeout_s: float = 900) -> dict[str, Any]:
        """Its JSON plus the exit code (a test failure naming the log when it does not finish)."""
        return _wait_for_json(sweep.proc, sweep.log, timeout_s, "chronav evaluate")


@pytest.fixture(scope="module")
def evaluate_runs() -> Iterator[EvaluateRuns]:
    """`chronav evaluate` sweeps for a module's tests, every process killed when the module ends."""
    with process_group() as group:
        yield EvaluateRuns(group)

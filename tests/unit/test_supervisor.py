"""The launcher's supervisor restarts crashed processes up to a limit and stops them all."""

from __future__ import annotations

import os
import time
from pathlib import Path

from tests.support import wait_until
from tools.supervisor import Supervisor


def test_crashing_process_is_restarted_until_the_limit(tmp_path: Path) -> None:
    sup = Supervisor(tmp_path / "logs", dict(os.environ), restart_limit=2)
    sup.add("crasher", "tests.unit.crash_helper", ["--exit", "3"])
    sup.start_all()
    try:
        wait_until(lambda: bool(sup.poll()) or sup.processes["crasher"].restarts >= 2, 20, message="restarts")
        wait_until(lambda: (sup.poll() or True) and sup.given_up() == ["crasher"], 20, message="give up")
        assert sup.processes["crasher"].exit_codes == [3, 3, 3]
        assert any("restart limit 2 reached" in e for e in sup.events)
    finally:
        sup.stop_all(timeout_s=2)


def test_stop_all_terminates_long_running_processes(tmp_path: Path) -> None:
    sup = Supervisor(tmp_path / "logs", dict(os.environ), restart_limit=0)
    sup.add("sleeper", "tests.unit.crash_helper", ["--sleep", "60"])
    sup.start_all()
    time.sleep(0.2)
    assert sup.processes["sleeper"].alive
    sup.stop_all(timeout_s=5)
    assert not sup.processes["sleeper"].alive
    assert sup.poll() == []  # stopping: no restart

"""A write outside the vocabulary is refused live, with a message naming the agent and the key.

Real processes on 127.0.0.1: a router, an agent run by the runtime (tests/integration/typo_agent.py,
the vocabulary's own ``now_S`` typo on its 5th step) and a second replica.  The refusal is seen the
way a user sees it: in the agent's log and in ``chronav dsr stats``; ``chronav dsr dump`` shows the
clock without the typo; the agent went on (its later writes arrive) and the other replica never
received anything to refuse.
"""

from __future__ import annotations

import json
import signal

import pytest
from typer.testing import CliRunner

from tests.integration.dsr_support import start_router
from tests.integration.fault_support import spawn_script, status_of
from tests.support import REPO_ROOT, wait_until
from tools.cli import app

pytestmark = pytest.mark.slow

SCENE = REPO_ROOT / "tests" / "data" / "eval_tiny.yaml"
REFUSAL = ("agent 'sim_robot' may not set attributes of 'clock': a clock node has no attribute 'now_S'; "
           "known: end_s, finished, mode, now_s, rate, start_s")


def test_a_typo_d_attribute_is_refused_live_and_the_agent_goes_on(procs, tmp_path) -> None:
    endpoint, _ = start_router(procs, tmp_path)
    env = {"CHRONAV_ZENOH_CONNECT": endpoint, "CHRONAV_ZENOH_LEASE_MS": "1000"}   # shipped write policy
    _, observer = spawn_script(procs, tmp_path, "human_observer", connect=endpoint, env=env,
                               script=[{"op": "wait", "names": ["clock"]}])
    wait_until(lambda: status_of(observer).get("script_done") is not None, 20, message="observer joined")
    status, log = tmp_path / "typo_agent.json", tmp_path / "typo_agent.log"
    agent = procs.spawn(["-m", "tests.integration.typo_agent", "--scene", str(SCENE), "--period", "0.05",
                         "-o", f"status={status}"], env=env, log_path=log)

    def agent_status() -> dict:
        try:
            return json.loads(status.read_text())
        except (OSError, ValueError):
            return {}

    wait_until(lambda: agent_status().get("steps") == 20 or agent.poll() is not None, 30, message="agent ran")
    assert agent.poll() is None, log.read_text()                    # the refusal did not end it
    mine = agent_status()
    assert mine["refused"] == 1 and mine["last_refusal"].startswith(REFUSAL)
    assert mine["clock"]["now_s"] == 20.0 and "now_S" not in mine["clock"]
    wait_until(lambda: REFUSAL in log.read_text(), 10, message="refusal logged")

    runner = CliRunner()
    # chronav dsr stats: the agent counts its refusal, beside the write policy's counters
    result = runner.invoke(app, ["dsr", "stats", "--connect", endpoint, "--json", "--timeout", "3"])
    assert result.exit_code == 0, result.output
    members = json.loads(result.stdout)["members"]
    sim = members["sim_robot"]["stats"]
    assert sim["rejects"] == {"vocabulary": 1} and REFUSAL in sim["last_reject"]
    other = members["human_observer"]["stats"]
    assert other["rejected"] == 0 and other["rejected_policy"] == 0      # nothing was ever sent to refuse
    # chronav dsr dump: the other replicas' clock went on from the agent's later writes, without the typo
    wait_until(lambda: _clock(runner, endpoint).get("now_s") == 20.0, 10, message="clock replicated")
    assert "now_S" not in _clock(runner, endpoint)
    # stopped as the launcher stops it: a clean exit, no abort in Zenoh's threads (agents/runtime/exit_guard.py)
    agent.send_signal(signal.SIGTERM)
    assert agent.wait(timeout=30) == 0, log.read_text()
    assert "FATAL" not in log.read_text() and "sim_robot stopped" in log.read_text()


def _clock(runner: CliRunner, endpoint: str) -> dict:
    result = runner.invoke(app, ["dsr", "dump", "--connect", endpoint, "--json", "--timeout", "3"])
    if result.exit_code != 0:
        return {}
    nodes = json.loads(result.stdout).get("nodes", [])
    return next((n.get("attrs", {}) for n in nodes if n.get("name") == "clock"), {})

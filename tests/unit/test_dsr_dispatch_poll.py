"""dispatch() polls briefly before it sleeps, only while changes come densely, and within its
CPU share (dsr.signals.SpinPolicy); CHRONAV_DSR_SPIN_US / _SPIN_SHARE_PCT set it per process,
and a bad value is named by the command line, not shown as a traceback."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time

import pytest

from dsr.errors import ConfigError
from dsr.signals import SignalHub, SpinPolicy
from tests.support import REPO_ROOT


def _post_later(hub: SignalHub, delay_s: float, value: int) -> None:
    threading.Timer(delay_s, lambda: hub.post([("node_deleted", (value,))])).start()


def _hub(policy: SpinPolicy) -> tuple[SignalHub, list[int]]:
    hub = SignalHub(policy)
    got: list[int] = []
    hub.connect("node_deleted", got.append)
    return hub, got


def test_the_policy_comes_from_the_environment_and_bad_values_name_the_variable() -> None:
    assert SpinPolicy.from_env({}) == SpinPolicy()
    assert SpinPolicy.from_env({"CHRONAV_DSR_SPIN_US": "0"}).window_us == 0
    assert SpinPolicy.from_env({"CHRONAV_DSR_SPIN_SHARE_PCT": " 10 "}).max_share_pct == 10
    for var, text in (("CHRONAV_DSR_SPIN_US", "fast"), ("CHRONAV_DSR_SPIN_US", "-1"),
                      ("CHRONAV_DSR_SPIN_SHARE_PCT", "150")):
        with pytest.raises(ConfigError, match=var):
            SpinPolicy.from_env({var: text})


def test_dense_changes_are_picked_up_by_polling_and_delivered() -> None:
    hub, got = _hub(SpinPolicy(window_us=300_000, max_share_pct=100, burst_ms=1000))
    _post_later(hub, 0.01, 1)
    assert hub.dispatch(timeout=5.0) == 1          # slept: nothing came before
    assert (hub.spin_hits, hub.spin_misses) == (0, 0)
    _post_later(hub, 0.02, 2)                        # the last change came within the window
    assert hub.dispatch(timeout=5.0) == 1 and got == [1, 2]
    assert hub.spin_hits == 1 and hub.spin_s > 0


def test_sparse_changes_never_poll() -> None:
    hub, got = _hub(SpinPolicy(window_us=5_000, max_share_pct=100, burst_ms=1000))
    for value in (1, 2):
        _post_later(hub, 0.1, value)
        assert hub.dispatch(timeout=5.0) == 1
    assert got == [1, 2] and (hub.spin_hits, hub.spin_misses, hub.spin_s) == (0, 0, 0.0)


def test_polling_stays_within_its_cpu_share_and_the_timeout() -> None:
    # credit: 10% of 100 ms = 10 ms of polling, though the window would allow 200 ms
    hub, _ = _hub(SpinPolicy(window_us=200_000, max_share_pct=10, burst_ms=100))
    _post_later(hub, 0.005, 1)
    assert hub.dispatch(timeout=5.0) == 1            # now dense
    start = time.monotonic()
    assert hub.dispatch(timeout=0.3) == 0            # nothing comes: poll, give up, sleep
    assert 0.29 <= time.monotonic() - start < 1.0
    assert hub.spin_misses == 1 and hub.spin_s < 0.05
    hub, _ = _hub(SpinPolicy(window_us=200_000, max_share_pct=100, burst_ms=1000))
    _post_later(hub, 0.005, 1)
    assert hub.dispatch(timeout=5.0) == 1
    start = time.monotonic()
    assert hub.dispatch(timeout=0.03) == 0           # the poll ends with the timeout
    assert time.monotonic() - start < 0.15 and hub.spin_s < 0.15


def test_a_zero_window_turns_polling_off() -> None:
    hub, got = _hub(SpinPolicy(window_us=0))
    for value in (1, 2, 3):
        _post_later(hub, 0.005, value)
        assert hub.dispatch(timeout=5.0) == 1
    assert got == [1, 2, 3] and hub.spin_hits + hub.spin_misses == 0


@pytest.mark.parametrize("var", ["CHRONAV_DSR_SPIN_US", "CHRONAV_DSR_MAX_VALUE_BYTES"])
def test_a_bad_dsr_variable_is_named_by_the_cli_without_a_traceback(var: str) -> None:
    # regression: both escaped `chronav plan` as tracebacks (the limits one at import time)
    env = {**os.environ, var: "fast"}
    result = subprocess.run([sys.executable, "-m", "tools.cli", "plan", "icra_usecase",
                             "--mission", "room:kitchen"], cwd=REPO_ROOT, env=env,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2, result.stderr
    assert f"{var}='fast'" in result.stderr and "Traceback" not in result.stderr

"""Endpoints and connection errors in a user's words (dsr/config.py, dsr/router.py)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from dsr import ConfigError, ZenohSettings
from dsr.config import check_endpoint, clean_zenoh_error
from tests.support import REPO_ROOT

RUST_ERROR = ("Unable to connect to any of [Single(tcp/127.0.0.1:49471)]!  at /root/.cargo/git/checkouts/"
              "zenoh-9c599d5ef3e0480e/cc83980/zenoh/src/net/runtime/orchestrator.rs:447.")


@pytest.mark.parametrize("endpoint", ["tcp/127.0.0.1:7447", "tcp/[::1]:7447", "tls/centre.local:7447",
                                      "tls/10.0.0.1:7447#root_ca_certificate=/etc/ca.pem", "unixsock-stream//tmp/z"])
def test_good_endpoints_pass(endpoint: str) -> None:
    assert check_endpoint(endpoint) == endpoint


@pytest.mark.parametrize(("endpoint", "message"), [
    ("garbage", "'garbage' is not an endpoint; expected PROTOCOL/HOST:PORT, e.g. tcp/127.0.0.1:7447"),
    ("127.0.0.1:7447", "'127.0.0.1:7447' is not an endpoint; expected PROTOCOL/HOST:PORT"),
    ("tcp/127.0.0.1", "'tcp/127.0.0.1': expected tcp/HOST:PORT, e.g. tcp/127.0.0.1:7447"),
    ("tcp/host:99999", "'tcp/host:99999': port 99999 is not between 1 and 65535"),
    ("tcp/host:0", "'tcp/host:0': port 0 is not between 1 and 65535"),
])
def test_bad_endpoints_say_the_expected_form(endpoint: str, message: str) -> None:
    with pytest.raises(ConfigError) as direct:
        check_endpoint(endpoint)
    assert str(direct.value).startswith(message)
    with pytest.raises(ConfigError) as from_env:       # one line naming the variable, no pydantic report
        ZenohSettings.from_env({"CHRONAV_ZENOH_CONNECT": endpoint})
    assert str(from_env.value) == f"CHRONAV_ZENOH_CONNECT: {direct.value}"


def test_zenoh_errors_lose_their_rust_source_path() -> None:
    assert clean_zenoh_error(RUST_ERROR) == "Unable to connect to any of [Single(tcp/127.0.0.1:49471)]"
    assert clean_zenoh_error("Timeout! at /x/y/orchestrator.rs:388:12") == "Timeout"


def test_open_timeout_bounds_the_handshake_only() -> None:
    conf = ZenohSettings(connect=["tcp/127.0.0.1:7447"], open_timeout_ms=1500).to_zenoh_config()
    assert json.loads(conf.get_json("transport/unicast/open_timeout")) == 1500
    assert json.loads(conf.get_json("connect/timeout_ms")) is None      # a refused connection fails at once


def test_router_flags_are_checked_in_one_line() -> None:
    for args, message in ((["--listen", "garbage"], "dsr.router: --listen 'garbage' is not an endpoint"),
                          (["--lease-ms", "5"], "dsr.router: --lease-ms: Input should be greater than or equal to 100")):
        result = subprocess.run([sys.executable, "-m", "dsr.router", *args], cwd=REPO_ROOT, capture_output=True,
                                text=True, timeout=60)
        assert result.returncode == 2 and result.stderr.startswith(message), result.stderr
        assert len(result.stderr.strip().splitlines()) == 1

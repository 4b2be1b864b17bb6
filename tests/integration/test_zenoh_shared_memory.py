"""chronav's Zenoh sessions leave Zenoh's shared-memory transport off unless asked.

Why it matters: with it on, a process that sends a message over 3 kB to a peer on the same host
gets a 16 MB pool in /dev/shm, and every process it talks to maps that pool and counts its pages
in its own RSS: about 100 MB of each agent's RSS in a launched run, and a 19 MB step in every
process, the router too, whenever one more pool comes into use (docs/long_runs.md).  A DSR delta
goes through the socket as fast.  Real sessions on 127.0.0.1 through a router on a free port.
"""

from __future__ import annotations

import threading
from pathlib import Path

import pytest

from dsr.config import ZenohSettings
from tools.ports import free_port

PAYLOAD = b"x" * 64_000     # well over the shared-memory transport's 3 kB threshold


def _zenoh_pools() -> set[str]:
    """The /dev/shm Zenoh segments this process has mapped."""
    return {line.split()[-1] for line in Path("/proc/self/maps").read_text().splitlines()
            if line.rstrip().endswith(".zenoh")}


def _exchange(shared_memory: bool | None) -> set[str]:
    """Route PAYLOAD from one client session to another; the Zenoh segments mapped meanwhile."""
    import zenoh

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    extra = {} if shared_memory is None else {"shared_memory": shared_memory}
    router = zenoh.open(ZenohSettings(mode="router", listen=[endpoint], **extra).to_zenoh_config())
    before = _zenoh_pools()
    try:
        sender = zenoh.open(ZenohSettings(connect=[endpoint], **extra).to_zenoh_config())
        receiver = zenoh.open(ZenohSettings(connect=[endpoint], **extra).to_zenoh_config())
        got = threading.Event()
        subscriber = receiver.declare_subscriber(
            "chronav/test/shm", lambda sample: got.set() if sample.payload.to_bytes() == PAYLOAD else None)
        try:
            for _ in range(100):     # until the subscription has reached the sender through the router
                sender.put("chronav/test/shm", PAYLOAD)
                if got.wait(0.05):
                    break
            assert got.is_set(), "the payload never arrived"
            return _zenoh_pools() - before
        finally:
            subscriber.undeclare()
            sender.close()
            receiver.close()
    finally:
        router.close()


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="reads /proc (Linux)")
def test_sessions_map_no_shared_memory_pool_by_default_and_do_when_asked() -> None:
    assert _exchange(None) == set(), "chronav's default sessions mapped Zenoh shared memory"
    assert _exchange(True), "with shared memory asked for, Zenoh maps its pools (the check can fail)"

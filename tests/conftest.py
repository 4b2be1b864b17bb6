"""Pytest fixtures shared by every test layer."""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest
from hypothesis import HealthCheck, settings

from tests.support import ProcessGroup, process_group

# Property tests judge results, not speed (speed goals live in tools/bench/bench_*.py): no per-example
# deadline, which a loaded 2-core machine would turn into flaky failures.
settings.register_profile("chronav", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("chronav")

# Unit tests never need a Rerun sink; system tests opt back in explicitly.
os.environ.setdefault("RERUN", "off")


@pytest.fixture
def procs() -> Iterator[ProcessGroup]:
    """Spawned subprocesses, killed (whole process group) when the test ends, pass or fail."""
    with process_group() as group:
        yield group

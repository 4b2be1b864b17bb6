"""Pytest fixtures shared by every test layer."""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest

from tests.support import ProcessGroup, process_group

# Unit tests never need a Rerun sink; system tests opt back in explicitly.
os.environ.setdefault("RERUN", "off")


@pytest.fixture
def procs() -> Iterator[ProcessGroup]:
    """Spawned subprocesses, killed (whole process group) when the test ends, pass or fail."""
    with process_group() as group:
        yield group

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


#: The longest test files outside tests/unit, longest first (`make test` prints its slowest tests:
#: keep this in step when a file grows).  `make test` hands files to its two workers in collection
#: order (--dist loadfile --no-loadscope-reorder); by default xdist would send the files with the
#: most tests first, which put the longest single-test launches last, one worker finishing them
#: alone for minutes while the other sat idle.  Longest first, the short files fill in at the end.
LONGEST_FIRST = (
    "tests/system/test_evaluate.py", "tests/system/test_center_day.py", "tests/system/test_faults.py",
    "tests/system/test_parity.py", "tests/system/test_plugin_package.py", "tests/system/test_center_b.py",
    "tests/system/test_icra_usecase.py", "tests/system/test_ros_bridge.py", "tests/system/test_map_ward.py",
    "tests/system/test_long_run.py", "tests/system/test_agenda_live.py", "tests/system/test_run_lifecycle.py",
    "tests/system/test_plugin_refusals.py", "tests/system/test_ros_console.py",
    "tests/system/test_recording_layers.py", "tests/integration/test_export_mcap.py",
)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Files of LONGEST_FIRST first, in its order; every other file after them, in collection order."""
    rank = {path: index for index, path in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::", 1)[0], len(rank)))


@pytest.fixture
def procs() -> Iterator[ProcessGroup]:
    """Spawned subprocesses, killed (whole process group) when the test ends, pass or fail."""
    with process_group() as group:
        yield group

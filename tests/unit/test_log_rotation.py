"""Issue 41: a real-time run's processes cut their own logs on the wall clock's hours
(dsr/log_rotation.py), without losing a line, and a cut that fails never stops them."""

from __future__ import annotations

import errno
import os
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from dsr.log_rotation import LOG_FILE_ENV, LOG_ROTATE_ENV, LogRotation, rotate_period_s, slot_start_s
from tools.system.supervisor import Supervisor

HOUR = 3600


class FakeClock:
    def __init__(self, now: float) -> None:
        self.now = now

    def __call__(self) -> float:
        return self.now


def _local(y: int, mo: int, d: int, h: int, mi: int, s: int = 0) -> float:
    return time.mktime((y, mo, d, h, mi, s, 0, 0, -1))


@pytest.fixture
def writer(tmp_path: Path) -> Iterator[tuple[Path, int]]:
    """An agent's log as the launcher opens it: a file in append mode on a descriptor."""
    path = tmp_path / "logs" / "executive.log"
    path.parent.mkdir()
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        yield path, fd
    finally:
        os.close(fd)


def test_the_log_is_cut_on_the_hour_and_every_line_is_kept(writer: tuple[Path, int]) -> None:
    path, fd = writer
    clock = FakeClock(_local(2026, 12, 5, 10, 59, 0))
    rotation = LogRotation(path, HOUR, clock=clock, fds=[fd])
    os.write(fd, b"10:59 before\n")
    assert rotation.maybe_rotate() is None                      # within the hour: nothing to do
    clock.now = _local(2026, 12, 5, 11, 0, 1)
    part = rotation.maybe_rotate()
    assert part == path.with_name("executive-20261205-1000.log")
    os.write(fd, b"11:00 after\n")                               # the same descriptor, now the new file
    assert part.read_text() == "10:59 before\n"
    current = path.read_text().splitlines()
    assert current[0] == "2026-12-05 11:00:01 log continued from executive-20261205-1000.log"   # the cut's time
    assert current[1] == "11:00 after"
    assert rotation.maybe_rotate() is None
    clock.now = _local(2026, 12, 5, 13, 30)                       # an hour with nothing cut in between
    assert rotation.maybe_rotate() == path.with_name("executive-20261205-1100.log")
    assert sorted(p.name for p in path.parent.iterdir()) == [
        "executive-20261205-1000.log", "executive-20261205-1100.log", "executive.log"]


def test_a_restarted_process_cuts_what_its_predecessor_left_in_an_earlier_hour(writer: tuple[Path, int]) -> None:
    path, fd = writer
    os.write(fd, b"the crashed agent's last lines\n")
    old = _local(2026, 12, 5, 9, 45)
    os.utime(path, (old, old))
    clock = FakeClock(_local(2026, 12, 5, 10, 2))
    rotation = LogRotation(path, HOUR, clock=clock, fds=[fd])
    assert rotation.maybe_rotate() == path.with_name("executive-20261205-0900.log")
    assert "crashed agent" not in path.read_text()


def test_an_empty_log_and_a_log_nobody_writes_here_are_left_alone(writer: tuple[Path, int], tmp_path: Path) -> None:
    path, fd = writer
    clock = FakeClock(_local(2026, 12, 5, 10, 30))
    rotation = LogRotation(path, HOUR, clock=clock, fds=[fd])
    clock.now += HOUR
    assert rotation.maybe_rotate() is None and list(path.parent.iterdir()) == [path]   # no empty parts
    other = tmp_path / "elsewhere.log"
    other.write_text("a terminal's process with the variables set by hand\n")
    stranger = LogRotation(other, HOUR, clock=clock, fds=[fd])     # fd writes to another file
    clock.now += HOUR
    assert stranger.maybe_rotate() is None and other.read_text().startswith("a terminal")


def test_a_cut_that_fails_keeps_the_output_where_it_was_and_is_tried_again(
        writer: tuple[Path, int], monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    path, fd = writer
    clock = FakeClock(_local(2026, 12, 5, 10, 30))
    rotation = LogRotation(path, HOUR, clock=clock, fds=[fd])
    os.write(fd, b"line 1\n")
    real_open = os.open

    def disk_full(*args: object, **kwargs: object) -> int:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "open", disk_full)
    clock.now = _local(2026, 12, 5, 11, 0, 5)
    assert rotation.maybe_rotate() is None
    assert "No space left on device" in caplog.text and "tried again at the next slot" in caplog.text
    os.write(fd, b"line 2\n")
    assert path.read_text() == "line 1\nline 2\n" and len(list(path.parent.iterdir())) == 1
    monkeypatch.setattr(os, "open", real_open)
    clock.now = _local(2026, 12, 5, 12, 0, 5)
    assert rotation.maybe_rotate() == path.with_name("executive-20261205-1100.log")


def test_a_second_part_of_one_slot_gets_its_own_name(writer: tuple[Path, int]) -> None:
    path, fd = writer
    taken = path.with_name("executive-20261205-1000.log")
    taken.write_text("cut by the agent's previous life\n")
    clock = FakeClock(_local(2026, 12, 5, 10, 10))
    rotation = LogRotation(path, HOUR, clock=clock, fds=[fd])
    os.write(fd, b"this life\n")
    clock.now = _local(2026, 12, 5, 11, 0, 1)
    assert rotation.maybe_rotate() == path.with_name("executive-20261205-1000-2.log")
    assert taken.read_text() == "cut by the agent's previous life\n"


def test_slots_start_on_the_local_hour() -> None:
    t = _local(2026, 12, 5, 10, 42, 17)
    assert slot_start_s(t, HOUR) == _local(2026, 12, 5, 10, 0)
    assert slot_start_s(t, 60) == _local(2026, 12, 5, 10, 42)


@pytest.mark.parametrize("raw, words", [("hourly", "whole number"), ("0", "divisor of a day"),
                                        ("7", "divisor of a day"), ("-3600", "divisor of a day")])
def test_a_bad_period_is_refused_in_the_users_words(raw: str, words: str) -> None:
    with pytest.raises(ValueError, match=words) as caught:
        rotate_period_s({LOG_ROTATE_ENV: raw})
    assert LOG_ROTATE_ENV in str(caught.value)


def test_rotation_is_on_only_when_the_launcher_names_the_file_and_the_period(tmp_path: Path) -> None:
    log_file = str(tmp_path / "agenda.log")
    assert LogRotation.from_env({}) is None
    assert LogRotation.from_env({LOG_FILE_ENV: log_file}) is None            # a fast run: one log a day
    assert LogRotation.from_env({LOG_ROTATE_ENV: "3600"}) is None             # run by hand: a terminal
    rotation = LogRotation.from_env({LOG_FILE_ENV: log_file, LOG_ROTATE_ENV: "3600"})
    assert rotation is not None and rotation.path == Path(log_file) and rotation.period_s == HOUR


def test_the_supervisor_tells_each_process_its_log_file(tmp_path: Path) -> None:
    supervisor = Supervisor(tmp_path / "logs", {"CHRONAV_GRAPH": "g"})
    managed = supervisor.add("agenda", "agents.agenda")
    assert managed.env[LOG_FILE_ENV] == str(tmp_path / "logs" / "agenda.log") == str(managed.log_path)


def test_parts_shorter_than_a_minute_are_named_to_the_second(tmp_path: Path) -> None:
    rotation = LogRotation(tmp_path / "router.log", 5)
    assert rotation.part_path(_local(2026, 12, 5, 10, 51, 35)).name == "router-20261205-105135.log"
    assert LogRotation(tmp_path / "router.log", HOUR).part_path(_local(2026, 12, 5, 10, 0)).name == "router-20261205-1000.log"


def test_a_disk_that_fills_after_the_new_part_is_made_still_moves_the_output(
        writer: tuple[Path, int], monkeypatch: pytest.MonkeyPatch) -> None:
    """The continuation line cannot be written (ENOSPC): the cut goes on, so the descriptors and the
    file named <name>.log stay one and the next hour is cut too."""
    path, fd = writer
    clock = FakeClock(_local(2026, 12, 5, 10, 30))
    rotation = LogRotation(path, HOUR, clock=clock, fds=[fd])
    os.write(fd, b"line 1\n")
    real_write = os.write

    def full(target: int, data: bytes) -> int:
        if b"continued" in data:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write(target, data)

    monkeypatch.setattr(os, "write", full)
    clock.now = _local(2026, 12, 5, 11, 0, 5)
    assert rotation.maybe_rotate() == path.with_name("executive-20261205-1000.log")
    monkeypatch.setattr(os, "write", real_write)
    os.write(fd, b"line 2\n")
    assert path.read_text() == "line 2\n"
    clock.now = _local(2026, 12, 5, 12, 0, 5)
    assert rotation.maybe_rotate() == path.with_name("executive-20261205-1100.log")

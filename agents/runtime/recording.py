"""A thin Rerun layer: one file per agent process, all sharing the run's recording id.

Why per-process files merged by the launcher (see shared notes on Rerun 0.41): it survives any
agent being SIGKILLed (the file keeps all but the last ~200 ms), needs no sink process to be up
first, and ``rerun rrd optimize`` turns the files into ONE recording because the recording id is
shared.  Every agent logs under its own entity subtree so rows never collide.  Algorithms never
call Rerun; agents hand their results to this layer.

Two timelines carry the same instant: ``sim_time`` (a duration since the scene day's midnight,
what tests and tools compute with) and ``clock`` (a timestamp: the scene's date plus that
duration, written as if the scene's local time were UTC).  Why both: Rerun prints a duration as
"+9h 35m 10s" but a timestamp as a clock, and a researcher reads the day by its clock
("09:35:10").  The viewer's default time zone is UTC, so the clock reads as the scene's own.
"""

from __future__ import annotations

import datetime as dt
import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

APP_ID = "chronav"
TIMELINE = "sim_time"
CLOCK_TIMELINE = "clock"
DEFAULT_DAY = dt.date(2026, 11, 25)   # only when no scene date is given (the scenes' own default)
#: the Rust log target of rerun's "no footer" warning (RecordingFile._save)
_FOOTER_WARNING_TARGET = "re_log_encoding::rrd::file_sink"
#: sim seconds per recording part (a run at real time rotates hourly, tools/week.py); unset: one part
ROTATE_ENV = "CHRONAV_RECORDING_ROTATE_S"
#: wall seconds between two flushes of a rotating (real-time) stream's batcher; Rerun's default is
#: 0.2 s.  Why longer: each flush writes one chunk per entity, about 1.6 kB of framing whatever it
#: holds, and a real-time agent flushing every 0.2 s wrote more framing than data (docs/long_runs.md,
#: "Disk in real time").  A SIGKILLed agent loses at most this much of its recording.
REALTIME_FLUSH_S = 2.0


class FramePacer:
    """When a layer an agent could draw at every loop is due again: at most once per ``period_s``
    of sim time (and at once if the clock went back: a new day).

    Why by sim time: agents loop at a fixed wall rate (50 Hz).  In a fast run one loop covers a
    second of sim time or more and every loop draws; in real time the same loop would draw fifty
    frames a sim second.  A real-time simulator drawing every loop wrote 270 MB an hour
    (docs/long_runs.md); drawn every ``period_s`` of sim time, a recording holds the same frames
    per sim hour at any rate."""

    def __init__(self, period_s: float) -> None:
        self.period_s = period_s
        self._last_s: float | None = None

    def due(self, sim_s: float) -> bool:
        last = self._last_s
        # (a millionth of a second of slack: ten 0.1 s ticks add up to 0.9999999999999999)
        if last is not None and last <= sim_s < last + self.period_s - 1e-6:
            return False
        self._last_s = sim_s
        return True


def clock_epoch_s(day: dt.date | None) -> float:
    """POSIX seconds of ``day``'s midnight read as UTC: the ``clock`` timeline's zero."""
    day = day or DEFAULT_DAY
    return dt.datetime(day.year, day.month, day.day, tzinfo=dt.UTC).timestamp()


class RecordingFile:
    """One Rerun stream and the file it writes, ``<run_dir>/rrd/<name>-<pid>.rrd``, rotated into
    ``<name>-<pid>-s<slot>.rrd`` parts (docs/long_runs.md) when ``CHRONAV_RECORDING_ROTATE_S`` is set.

    Why a class of its own, apart from the agent-facing Recorder: a process that runs every agent
    (in-process, tools/inprocess.py) writes them all through ONE stream.  rerun-sdk 0.41 never
    frees a stream once it is made (rerun-io/rerun#2116: its threads and buffers stay after
    ``disconnect()``, about 3 MB and two threads each), so seven streams a day grew an in-process
    week by 20 MB a day; one stream a day is within the noise.  Launched, each agent process owns
    one, as before.  Static rows and the blueprint are remembered and written again into each new
    part, so every part opens on its own."""

    def __init__(self, name: str, run_dir: Path, recording_id: str) -> None:
        # Rerun warns at every part that it has no footer (below): a warning meant for files read
        # as they are, which ours never are.  Only effective before rerun is first imported.
        os.environ.setdefault("RUST_LOG", f"warn,{_FOOTER_WARNING_TARGET}=error")
        import rerun as rr

        self.name = name
        self.rotate_s = _rotate_s()
        out_dir = run_dir / "rrd"
        out_dir.mkdir(parents=True, exist_ok=True)
        # pid in the name: a restarted agent must not overwrite what its predecessor recorded.
        self.path = out_dir / f"{name}-{os.getpid()}.rrd"
        batching = None if self.rotate_s is None else rr.ChunkBatcherConfig(flush_tick=REALTIME_FLUSH_S)
        self.stream: Any = rr.RecordingStream(APP_ID, recording_id=recording_id, batcher_config=batching)
        self._save()
        self._slot: int | None = None
        self._statics: list[tuple[str, tuple[Any, ...]]] = []
        self._blueprint: Any = None

    def at(self, sim_s: float) -> None:
        """Rotate to the part of ``sim_s`` if rotating and it starts a new slot."""
        if self.rotate_s is not None and int(sim_s // self.rotate_s) != self._slot:
            self._rotate(int(sim_s // self.rotate_s))

    def _rotate(self, slot: int) -> None:
        """Close the current part and go on in the part of ``slot``; the unslotted first part
        (rows logged before the clock was set) is dropped once rotated: its static rows follow."""
        first = self._slot is None
        previous = self.path
        self.path = previous.parent / f"{self.name}-{os.getpid()}-s{slot:03d}.rrd"
        self._save()
        self._slot = slot
        if self._blueprint is not None:
            self.stream.send_blueprint(self._blueprint)
        for entity, archetypes in self._statics:
            self.stream.log(entity, *archetypes, static=True)
        if first:
            previous.unlink(missing_ok=True)

    def _save(self) -> None:
        """Write from now on to ``self.path``, without the footer (the RRD manifest).

        Why no footer: to write it at the end, the SDK keeps every chunk's entry in memory for as
        long as the file is open (measured: ~0.35 kB a chunk; an agent flushing a few entities
        every 200 ms grew 5-16 MB an hour in a real-time soak, docs/long_runs.md).  A part is never
        read as it is: the run merges its parts with ``rerun rrd optimize``, which writes the
        footer of the file users open (as it already did for the parts of a SIGKILLed agent)."""
        self.stream.save(self.path, write_footer=False)

    def remember_static(self, entity: str, archetypes: tuple[Any, ...]) -> None:
        if self.rotate_s is not None:
            self._statics.append((entity, archetypes))

    def send_blueprint(self, blueprint: Any) -> None:
        self.stream.send_blueprint(blueprint)
        self._blueprint = blueprint

    def close(self) -> None:
        """Flush what is left and close the file."""
        if self.stream is not None:
            self.stream.disconnect()
            self.stream = None


def shared_recording_file(name: str, run_dir: Path | None, recording_id: str | None) -> RecordingFile | None:
    """The one stream every Recorder of an in-process run writes through, or None when not recording."""
    if not recording_enabled(run_dir, recording_id):
        return None
    assert run_dir is not None and recording_id is not None
    return RecordingFile(name, run_dir, recording_id)


def recording_enabled(run_dir: Path | None, recording_id: str | None) -> bool:
    """Recording is on for a run directory and recording id, unless ``RERUN=off``."""
    return bool(run_dir and recording_id and os.environ.get("RERUN", "on") != "off")


class Recorder:
    """Logs to ``<run_dir>/rrd/<agent>-<pid>.rrd``; a no-op when disabled (tests, RERUN=off).

    With ``file`` (an in-process run's shared RecordingFile) it logs through that stream instead,
    under its own entities and clock, and leaves closing the file to the file's owner."""

    def __init__(self, agent: str, run_dir: Path | None, recording_id: str | None,
                 day: dt.date | None = None, file: RecordingFile | None = None) -> None:
        self.agent = agent
        self._epoch_s = clock_epoch_s(day)
        self._owns_file = file is None
        if file is None and recording_enabled(run_dir, recording_id):
            assert run_dir is not None and recording_id is not None
            file = RecordingFile(agent, run_dir, recording_id)
        else:
            _rotate_s()   # a bad rotation setting is refused whoever writes the file
        self._file = file
        self.enabled = file is not None
        self._rec: Any = None if file is None else file.stream

    @property
    def path(self) -> Path | None:
        """The part being written now (None when not recording)."""
        return None if self._file is None else self._file.path

    def set_day(self, day: dt.date | None) -> None:
        """The scene's date, for the ``clock`` timeline (set before the first ``set_time``)."""
        self._epoch_s = clock_epoch_s(day)

    def set_time(self, sim_s: float) -> None:
        """Seconds since local midnight of the sim day, on both timelines (see the module doc)."""
        if self._rec is not None:
            import rerun as rr

            assert self._file is not None
            self._file.at(sim_s)
            rr.set_time(TIMELINE, duration=sim_s, recording=self._rec)
            # Integer nanoseconds: float epoch seconds would round 0.1 s steps to ~200 ns.
            rr.set_time(CLOCK_TIMELINE, timestamp=_ns(self._epoch_s, sim_s), recording=self._rec)

    def log(self, entity: str, *archetypes: Any, static: bool = False) -> None:
        if self._rec is not None:
            self._rec.log(entity, *archetypes, static=static)
            if static:
                assert self._file is not None
                self._file.remember_static(entity, archetypes)

    def scalar(self, entity: str, value: float) -> None:
        if self._rec is not None:
            import rerun as rr

            self._rec.log(entity, rr.Scalars(float(value)))

    def event(self, text: str, level: str = "INFO") -> None:
        """Agent decisions as text, one log per agent under ``events/<agent>``, written
        ``"HH:MM[:SS] agent: message"`` (the clock first when the agent gave it): the viewer's
        event table then reads by itself, with no time or entity column."""
        if self._rec is not None:
            import rerun as rr

            self._rec.log(f"events/{self.agent}", rr.TextLog(event_text(self.agent, text),
                                                             level=getattr(rr.TextLogLevel, level)))

    def line_strip(self, entity: str, points: Sequence[Sequence[float]], color: Sequence[int],
                   radius: float = 0.03, static: bool = False) -> None:
        if self._rec is not None and len(points) >= 2:
            import rerun as rr

            self.log(entity, rr.LineStrips2D([list(map(list, points))], colors=[color], radii=radius), static=static)

    def clear(self, entity: str, recursive: bool = True) -> None:
        """Nothing is at ``entity`` from now on (a layer that stopped being true)."""
        if self._rec is not None:
            import rerun as rr

            self._rec.log(entity, rr.Clear(recursive=recursive))

    def send_blueprint(self, blueprint: Any) -> None:
        if self._file is not None:
            self._file.send_blueprint(blueprint)

    def flush(self) -> None:
        if self._rec is not None:
            self._rec.flush()

    def close(self) -> None:
        """Flush what is left and close the file; a shared file is its
        owner's to close, so this recorder only stops logging to it."""
        if self._file is not None and self._owns_file:
            self._file.close()
        self._file = None
        self._rec = None


CLOCK_PREFIX = re.compile(r"^(-?\d{2}:\d{2}(?::\d{2})?) ")


def event_text(agent: str, text: str) -> str:
    """``"09:30:01 m0930 started"`` -> ``"09:30:01 executive: m0930 started"``; a clock given
    as ``HH:MM`` (``format_clock`` on whole minutes) is written ``HH:MM:00``, so every event
    reads the same way."""
    found = CLOCK_PREFIX.match(text)
    if found is None:
        return f"{agent}: {text}"
    clock = found.group(1) if found.group(1).count(":") == 2 else f"{found.group(1)}:00"
    return f"{clock} {agent}: {text[found.end():]}"


def _ns(epoch_s: float, sim_s: float) -> Any:
    import numpy as np

    return np.datetime64(int(round(epoch_s)) * 1_000_000_000 + int(round(sim_s * 1e9)), "ns")


def _rotate_s() -> float | None:
    """``CHRONAV_RECORDING_ROTATE_S``: sim seconds per part (>= 60), or None (one part)."""
    raw = os.environ.get(ROTATE_ENV, "").strip()
    if not raw:
        return None
    try:
        value = float(raw)
    except ValueError:
        raise ValueError(f"{ROTATE_ENV}={raw!r}: give the sim seconds per recording part, e.g. 3600") from None
    if not value >= 60.0:
        raise ValueError(f"{ROTATE_ENV}={raw!r}: a part spans at least 60 sim seconds")
    return value


def part_slot(path: Path) -> int | None:
    """The slot of a rotated part (``<agent>-<pid>-s009.rrd`` -> 9), None for an unrotated one."""
    found = re.search(r"-s(\d{3,})$", path.stem)
    return int(found.group(1)) if found else None

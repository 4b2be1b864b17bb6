"""Clock times: one syntax for scenes, agendas, missions and the command line.

Why one module: "HH:MM" is typed by staff in scene files, agenda files and on the command line
(`chronav path --at 11:15`), and written back in every message; a second parser that accepted
``9`` where the first refused it is exactly the kind of drift users trip over.  Times are seconds
since local midnight of the sim day (float); ``"24:00"`` is the end of the day.
"""

from __future__ import annotations

import functools
import re
from typing import Annotated

from pydantic import AfterValidator, Field

CLOCK_PATTERN = re.compile(r"^(\d{1,2}):(\d{2})(?::(\d{2}))?$")
SECONDS_PER_DAY = 86400.0


def parse_clock(text: str) -> float:
    """``"HH:MM"`` or ``"HH:MM:SS"`` -> seconds since midnight; ``"24:00"`` is the end of the day."""
    if isinstance(text, str) and len(text) <= 32:
        return _parse_clock_cached(text)
    return _parse_clock(text)


def _parse_clock(text: object) -> float:
    match = CLOCK_PATTERN.match(text.strip()) if isinstance(text, str) else None
    if not match:
        shown = text if isinstance(text, str) and len(text) <= 40 else f"{str(text)[:40]}..."
        raise ValueError(f"{shown!r} is not a clock time (use HH:MM or HH:MM:SS, e.g. 09:30)")
    hours, minutes, seconds = int(match[1]), int(match[2]), int(match[3] or 0)
    if (hours, minutes, seconds) != (24, 0, 0) and (hours > 23 or minutes > 59 or seconds > 59):
        raise ValueError(f"{text!r} is not a valid clock time (00:00 to 24:00)")
    return float(hours * 3600 + minutes * 60 + seconds)


# A scripted person's waypoint times are read at every step of the crowd: replaying the day up
# to 11:15 (what `chronav path` does offline) parsed them ~50,000 times on icra_usecase.
# Errors are not cached (lru_cache keeps only returned values).
_parse_clock_cached = functools.lru_cache(maxsize=1024)(_parse_clock)


def format_clock(seconds: float) -> str:
    """Seconds since midnight -> ``"HH:MM:SS"``, for messages and tables.

    Why always with seconds: a column or a log where some times read ``11:00`` and others
    ``11:00:30`` is hard to scan, and a reader cannot tell a whole minute from a dropped field."""
    whole = int(round(seconds))
    sign = "-" if whole < 0 else ""
    whole = abs(whole)
    hours, rest = divmod(whole, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{sign}{hours:02d}:{minutes:02d}:{secs:02d}"


def format_clock_minutes(seconds: float) -> str:
    """Seconds since midnight -> ``"HH:MM"``, the minute it falls in (seconds dropped, not rounded):
    for times written into a scene or an agenda change, whose fields are whole minutes."""
    minutes = int(seconds // 60)
    return f"{minutes // 60:02d}:{minutes % 60:02d}"


def _checked_clock(value: str) -> str:
    parse_clock(value)
    return value


# A clock time checked where it is declared, so every model that uses one validates it the same way.
ClockTime = Annotated[str, AfterValidator(_checked_clock), Field(description="local clock time HH:MM[:SS]")]

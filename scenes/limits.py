"""The bounds chronav puts on what it reads: one table, documented in docs/limits.md.

Why one module: every input boundary (scene and agenda YAML, .ics calendars, names typed on the
command line, the cost grid a scene asks for) must refuse hostile or careless input within
bounded time and memory, and a person who hits a bound must be able to find it, with its
default and how to raise it, in one place.  ``tests/unit/test_limits_doc.py`` checks that
docs/limits.md gives exactly these names and defaults.

Each limit can be raised (or lowered) for one process with an environment variable
``CHRONAV_LIMIT_<NAME>`` (e.g. ``CHRONAV_LIMIT_GRID_CELLS=50000000``); a value that is not a
positive whole number is an error naming the variable, never silently ignored.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass

from scenes.errors import SourceError

ENV_PREFIX = "CHRONAV_LIMIT_"


class LimitConfigError(SourceError):
    """A ``CHRONAV_LIMIT_*`` variable that is not a positive whole number (reported like a bad file)."""


@dataclass(frozen=True)
class Limit:
    """One bound: its name (lower case, the env suffix upper-cased), default, unit and purpose."""

    name: str
    default: int
    unit: str
    what: str

    @property
    def env(self) -> str:
        return ENV_PREFIX + self.name.upper()

    def value(self, environ: Mapping[str, str] | None = None) -> int:
        """The bound in force: the environment's value if set, else the default."""
        env = os.environ if environ is None else environ
        raw = env.get(self.env, "").strip()
        if not raw:
            return self.default
        # ASCII digits only: str.isdigit() is also true of "²" and "٣", which int() refuses or reads.
        if not (raw.isascii() and raw.isdigit()) or len(raw) > 18 or int(raw) <= 0:
            raise LimitConfigError(f"{self.env}={raw[:40]!r}", None, None, "",
                                   f"expected a positive whole number of {self.unit} (default {self.default})")
        return int(raw)


YAML_BYTES = Limit("yaml_bytes", 4 * 1024 * 1024, "bytes", "size of one YAML file (scene, agenda, write policy)")
YAML_DEPTH = Limit("yaml_depth", 64, "levels", "nesting of mappings and lists in a YAML file")
YAML_NODES = Limit("yaml_nodes", 100_000, "values",
                   "values in a YAML file after expanding its aliases (*name); stops 'billion laughs'")
YAML_INT_DIGITS = Limit("yaml_int_digits", 30, "digits", "digits of one integer in a YAML file")
TEXT_CHARS = Limit("text_chars", 10_000, "characters", "one text value (a description, a YAML scalar)")
NAME_CHARS = Limit("name_chars", 100, "characters",
                   "a name or id: rooms, objects, people, doors, missions, activities, participants")
ICS_BYTES = Limit("ics_bytes", 4 * 1024 * 1024, "bytes", "size of one .ics calendar file")
RECURRENCE_STEPS = Limit("recurrence_steps", 100_000, "steps",
                         "steps a recurrence rule may take from its first occurrence to the end of the "
                         "simulated day (FREQ=SECONDLY without COUNT/UNTIL would take millions)")
RECURRENCE_DATES = Limit("recurrence_dates", 5_000, "dates",
                         "RDATE and EXDATE values in one .ics file (each is expanded into a copy of its event)")
ACTIVITIES_PER_DAY = Limit("activities_per_day", 2_000, "activities", "activities on one simulated day")
GRID_CELLS = Limit("grid_cells", 16_000_000, "cells",
                   "cells of a scene's cost grid (64 MB per layer at 4 bytes a cell)")
TRAJECTORY_SAMPLES = Limit("trajectory_samples", 2_000_000, "samples", "rows of a trajectory CSV")
CROWD_ROWS = Limit("crowd_rows", 500_000, "annotations",
                   "lines of one recorded-pedestrian file a scene replays (scene from-crowd, routine: replay)")
CROWD_PEOPLE = Limit("crowd_people", 2_000, "people", "distinct people in one recorded-pedestrian file")

LIMITS: tuple[Limit, ...] = (YAML_BYTES, YAML_DEPTH, YAML_NODES, YAML_INT_DIGITS, TEXT_CHARS, NAME_CHARS,
                             ICS_BYTES, RECURRENCE_STEPS, RECURRENCE_DATES, ACTIVITIES_PER_DAY, GRID_CELLS, TRAJECTORY_SAMPLES,
                             CROWD_ROWS, CROWD_PEOPLE)

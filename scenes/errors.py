"""The one located error of every input file chronav reads (YAML, .ics, trajectory CSV).

Why its own module: the YAML reader, the agenda readers, the trajectory reader and the input
limits (a bad ``CHRONAV_LIMIT_*`` variable) all raise it, and every command prints it the same
way, ``file:line:col: key: message``, and exits non-zero.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SourceError(Exception):
    """An input-file error a person can act on: file, line, column, key path and message.

    ``line``/``column`` are 1-based; None when the problem concerns the whole file (the column
    is also None for line-oriented formats such as .ics)."""

    file: str
    line: int | None
    column: int | None
    key: str
    message: str

    def __str__(self) -> str:
        where = self.file
        if self.line is not None:
            where += f":{self.line}" + (f":{self.column}" if self.column is not None else "")
        return f"{where}: {self.key}: {self.message}" if self.key else f"{where}: {self.message}"

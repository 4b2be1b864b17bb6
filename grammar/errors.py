"""Typed errors of the grammar package.

Why a position on every error: grammar files are written by hand by the people who run the centre;
an error they can act on must say which file, which line and column, and what was expected there.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SourcePos:
    """Where something was written: 1-based line and column in ``file``."""

    file: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"


MAX_MESSAGE_CHARS = 400
"""Longest error message kept: a message quoting a 5 MB token must not flood a terminal."""

MAX_PATH_CHARS = 4096
"""A file path is quoted whole up to this length (Linux's PATH_MAX): a path cut in the middle
("…/et…") cannot be found or fixed, while a longer one is not a path."""


def shorten(text: str, limit: int = 60) -> str:
    """``text`` cut to ``limit`` characters, marked with an ellipsis (names quoted in messages)."""
    return text if len(text) <= limit else text[:limit - 1] + "…"


class GrammarError(Exception):
    """A grammar, target or mission text that cannot be used, with the place of the first problem.

    ``str(err)`` is ``file:line:col: message`` so that editors and CI logs can jump to it; when
    there is no place in the file (a file that cannot be read), ``file: message``.
    """

    def __init__(self, message: str, file: str = "<string>", line: int = 0, column: int = 0, *,
                 limit: int = MAX_MESSAGE_CHARS) -> None:
        self.message = shorten(message, limit)
        self.file = file
        self.line = line
        self.column = column
        super().__init__(str(self))

    @classmethod
    def at(cls, pos: SourcePos | None, message: str, *, limit: int = MAX_MESSAGE_CHARS) -> GrammarError:
        if pos is None:
            return cls(message, limit=limit)
        return cls(message, pos.file, pos.line, pos.column, limit=limit)

    def __str__(self) -> str:
        if self.line <= 0:
            return f"{self.file}: {self.message}"
        return f"{self.file}:{self.line}:{self.column}: {self.message}"


@dataclass(frozen=True)
class GrammarWarning:
    """Something read as AGM reads it but probably not meant so (``DormantFoo`` = dormant rule ``Foo``)."""

    pos: SourcePos
    message: str

    def __str__(self) -> str:
        return f"{self.pos}: warning: {self.message}"


class MissionError(ValueError):
    """A mission string that does not name a known kind of mission or is malformed."""


class PlanningError(Exception):
    """A grammar/world combination the planner cannot work on (e.g. a rule that needs an unsupported feature)."""

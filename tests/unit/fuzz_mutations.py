"""Hypothesis strategies that break valid input files the way people and disks do.

Why mutate shipped files rather than only generate random text: random text is refused by the
first line of any parser, while a valid file with one line deleted, duplicated or moved, one
value replaced by a strange one, or a few stray bytes, reaches the deep checks (schemas,
geometry, recurrences, time zones) where unexpected exceptions hide.
"""

from __future__ import annotations

import os
import re

from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

# Values that have crashed parsers before: empty, null, huge, non-finite, wrong type, YAML tags
# and anchors, impossible dates and times, control and non-ASCII characters.
NASTY_VALUES: tuple[str, ...] = (
    "", "~", "null", "-1", "0", "-0.0", "1e309", "-1e309", ".nan", ".inf", "-.inf", "nan", "inf",
    "1e-400", "99999999999999999999999", "0x1F", "1_000", "[]", "{}", "[1, 2]", "[[0, 0]]", "'x'",
    '"\\u0000"', "yes", "no", "25:61", "24:00", "23:59:60", "-01:00", "2026-02-30", "9999-12-31",
    "0000-01-01", "&a x", "*a", "!!binary AAAA", "!!python/object:os.system", "!!set {a}", "<<: *a",
    "\t", "é", "\U0001f600", "{a: [}", "- -", "?", "|", ">", "%", "@", "`", "\\", "\r", "\x00",
    "TZID=Mars/Olympus", "FREQ=SECONDLY", "FREQ=DAILY;COUNT=-1", "20261125T250000", "P-1D", "PT99999H",
)

_TOKEN = re.compile(r"[A-Za-z0-9_.:+\-/]+")


def fuzz_settings(examples: int) -> settings:
    """Deterministic by default (a CI run never fails by luck); CHRONAV_FUZZ_EXAMPLES=N with
    CHRONAV_FUZZ_RANDOM=1 explores further when hunting bugs locally."""
    hunting = os.environ.get("CHRONAV_FUZZ_RANDOM") == "1"
    return settings(max_examples=int(os.environ.get("CHRONAV_FUZZ_EXAMPLES", examples)), deadline=None,
                    database=None, derandomize=not hunting,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def _lines(text: str) -> list[str]:
    return text.splitlines(keepends=True) or [""]


@st.composite
def mutated_text(draw: st.DrawFn, text: str, max_ops: int = 3) -> str:
    """``text`` after 1..max_ops random edits of lines, tokens and characters."""
    for _ in range(draw(st.integers(1, max_ops))):
        lines = _lines(text)
        op = draw(st.sampled_from(("delete", "duplicate", "swap", "move", "token", "token", "value",
                                   "insert", "truncate", "indent", "char")))
        i = draw(st.integers(0, len(lines) - 1))
        j = draw(st.integers(0, len(lines) - 1))
        if op == "delete":
            del lines[i]
        elif op == "duplicate":
            lines.insert(j, lines[i])
        elif op == "swap":
            lines[i], lines[j] = lines[j], lines[i]
        elif op == "move":
            lines.insert(j, lines.pop(i))
        elif op == "indent":
            line = lines[i]
            indent = draw(st.sampled_from(("  ", "\t", " ")))
            lines[i] = line.lstrip(" \t") if line[:1] in (" ", "\t") else indent + line
        elif op in ("token", "value"):
            tokens = list(_TOKEN.finditer(text))
            if tokens:
                victim = draw(st.sampled_from(tokens))
                if op == "token":  # a value from elsewhere in the same file: right syntax, wrong place
                    replacement = draw(st.sampled_from(tokens)).group(0)
                else:
                    replacement = draw(st.one_of(st.sampled_from(NASTY_VALUES),
                                                 st.floats(allow_nan=True).map(repr),
                                                 st.integers(-(10**20), 10**20).map(str)))
                text = text[:victim.start()] + replacement + text[victim.end():]
                continue
        elif op == "insert":
            at = draw(st.integers(0, len(text)))
            text = text[:at] + draw(st.text(max_size=12)) + text[at:]
            continue
        elif op == "truncate":
            text = text[:draw(st.integers(0, len(text)))]
            continue
        else:  # char: one punctuation character somewhere
            at = draw(st.integers(0, max(0, len(text) - 1)))
            text = text[:at] + draw(st.sampled_from(list(":-[]{}#,'\"\n\t&*!|>%@`=;()<>"))) + text[at + 1:]
            continue
        text = "".join(lines)
    return text


@st.composite
def mutated_bytes(draw: st.DrawFn, text: str, max_ops: int = 3) -> bytes:
    """Like :func:`mutated_text`, encoded, sometimes with raw bytes spliced in (not UTF-8, NULs)."""
    data = draw(mutated_text(text, max_ops)).encode("utf-8")
    if draw(st.integers(0, 4)) == 0:
        at = draw(st.integers(0, len(data)))
        data = data[:at] + draw(st.binary(min_size=1, max_size=8)) + data[at:]
    return data


def token_soup(text: str, extra: tuple[str, ...] = ()) -> st.SearchStrategy[str]:
    """Random text made of the file's own words and syntax: right vocabulary, no structure."""
    words = sorted({m.group(0) for m in _TOKEN.finditer(text)}) or ["x"]
    pieces = st.sampled_from([*words, *extra, " ", "\n", "  ", "- ", ": ", ",", "{", "}", "[", "]", "(", ")"])
    return st.lists(pieces, max_size=60).map("".join)

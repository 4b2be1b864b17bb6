"""Property tests at the input bounds (scenes/limits.py): deep, large, aliased and recurring input
is either read correctly or refused with a located error naming the limit, and quickly.

Each strategy reaches past its bound (nesting to 3,000 levels, aliases to 12^12 values, values of
60,000 characters, 9,000-digit integers, recurrence rules of every frequency started up to a year
before the simulated day), so the refusal path is exercised, not only the happy one.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterator
from zoneinfo import ZoneInfo

import pytest
from hypothesis import given
from hypothesis import strategies as st

from agents.lib.agenda import AgendaSourceError, parse_ics
from agents.lib.agenda.ics_source import recurrence_steps
from scenes.limits import RECURRENCE_STEPS, TEXT_CHARS, YAML_DEPTH, YAML_INT_DIGITS, YAML_NODES
from scenes.yamlio import SourceError, load_located
from tests.unit.fuzz_mutations import fuzz_settings

MADRID = ZoneInfo("Europe/Madrid")
DAY = dt.date(2026, 11, 25)


@fuzz_settings(40)
@given(depth=st.integers(1, 3000), block=st.booleans())
def test_nesting_is_read_or_refused_at_the_depth_limit(depth: int, block: bool) -> None:
    depth = min(depth, 300) if block else depth  # block style: 300 levels are already 90 KB of indentation
    if block:
        text = "".join(f"{'  ' * level}k:\n" for level in range(depth)) + f"{'  ' * depth}1\n"
    else:
        text = "v: " + "[" * depth + "]" * depth + "\n"
    try:
        located = load_located(text, "deep.yaml")
    except SourceError as exc:
        assert f"nested more than {YAML_DEPTH.default} levels deep" in exc.message
        assert exc.line is not None and exc.line >= 1
        assert depth >= YAML_DEPTH.default - 1
        return
    assert depth <= YAML_DEPTH.default
    value, levels = (located.data if block else located.data["v"]), 0
    while isinstance(value, dict | list):
        levels += 1
        if not value:
            break
        value = value["k"] if isinstance(value, dict) else value[0]
    assert levels == depth


@fuzz_settings(25)
@given(levels=st.integers(1, 12), fanout=st.integers(1, 12))
def test_aliases_expand_within_the_budget_or_are_refused(levels: int, fanout: int) -> None:
    lines = [f"a0: &a0 [{', '.join(['x'] * fanout)}]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * fanout)}]" for i in range(1, levels)]
    text = "\n".join(lines) + "\n"
    produced = sum(fanout ** (i + 1) * (1 + sum(fanout ** -k for k in range(1, i + 1))) for i in range(levels))
    try:
        located = load_located(text, "laughs.yaml")
    except SourceError as exc:
        assert "expands to more than" in exc.message and YAML_NODES.env in exc.message
        assert produced > YAML_NODES.default / 2  # refused only when it is really large
        return
    leaves = located.data[f"a{levels - 1}"]
    for _ in range(levels - 1):
        leaves = [item for sub in leaves for item in sub]
    assert len(leaves) == fanout ** levels


@fuzz_settings(30)
@given(chars=st.integers(0, 60_000), digits=st.integers(1, 9_000))
def test_long_values_and_long_integers_are_bounded(chars: int, digits: int) -> None:
    try:
        located = load_located(f"text: '{'a' * chars}'\n", "long.yaml")
        assert len(located.data["text"]) == chars <= TEXT_CHARS.default
    except SourceError as exc:
        assert chars > TEXT_CHARS.default and TEXT_CHARS.env in exc.message and exc.key == "text"
    try:
        located = load_located(f"n: {'7' * digits}\n", "int.yaml")
        assert located.data["n"] == int("7" * digits) and digits <= YAML_INT_DIGITS.default
    except SourceError as exc:
        assert digits > YAML_INT_DIGITS.default and YAML_INT_DIGITS.env in exc.message and exc.line == 1


FREQUENCIES = ("SECONDLY", "MINUTELY", "HOURLY", "DAILY", "WEEKLY", "MONTHLY", "YEARLY")


@pytest.fixture(scope="module")
def small_step_limit() -> Iterator[int]:
    """A low recurrence bound, so that accepted rules are cheap to check against the estimate."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(RECURRENCE_STEPS.env, "3000")
        yield 3000


@fuzz_settings(60)
@given(freq=st.sampled_from(FREQUENCIES), interval=st.integers(1, 5), days_before=st.integers(0, 400),
       end=st.sampled_from(["", ";COUNT=5", ";COUNT=100000000", ";UNTIL=20261126T000000Z"]),
       by=st.sampled_from(["", ";BYHOUR=9,10", ";BYDAY=MO,WE", ";BYMINUTE=0,30"]))
def test_recurrences_expand_over_the_day_or_are_refused(small_step_limit: int, freq: str, interval: int,
                                                        days_before: int, end: str, by: str) -> None:
    start = dt.datetime.combine(DAY - dt.timedelta(days=days_before), dt.time(9, 0))
    rule = f"FREQ={freq};INTERVAL={interval}{end}{by}"
    text = "\r\n".join(["BEGIN:VCALENDAR", "VERSION:2.0", "PRODID:-//t//EN", "BEGIN:VEVENT", "UID:r",
                        f"DTSTART;TZID=Europe/Madrid:{start:%Y%m%dT%H%M%S}", "DURATION:PT1S", f"RRULE:{rule}",
                        "X-CHRONAV-OBJECT:tv", "END:VEVENT", "END:VCALENDAR", ""])
    agenda = parse_ics(text, "r.ics")
    try:
        occurrences = agenda.occurrences(DAY, MADRID)
    except AgendaSourceError as exc:
        assert "RECURRENCE_STEPS" in str(exc) and f"RRULE:FREQ={freq}" in str(exc)
        return
    day_start = dt.datetime.combine(DAY, dt.time(0, 0), tzinfo=MADRID)
    assert all(day_start <= o.start < day_start + dt.timedelta(days=1) for o in occurrences)
    (rrule,) = agenda.events[0].rrules
    from icalendar import vRecur

    estimate = recurrence_steps(vRecur.from_ical(rrule), agenda.events[0].start, day_start + dt.timedelta(days=2))
    assert estimate <= small_step_limit
    assert len(occurrences) <= estimate

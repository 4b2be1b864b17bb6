"""iCalendar agendas: recurrence, time zones (incl. DST days), exceptions, cancellations, errors."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import pytest

from agents.lib.agenda import (ActivityState, AgendaDay, IcsAgenda, AgendaSourceError, AgendaValidationError, expand_day,
                           load_agenda_file, load_ics_file, parse_ics)

DATA = Path(__file__).resolve().parents[1] / "data"
SCENES = Path(__file__).resolve().parents[2] / "scenes"
OBJECTS = {"tv", "round_table"}
H = 3600.0


@pytest.fixture(scope="module")
def therapy() -> IcsAgenda:
    return load_ics_file(DATA / "agenda_daily_therapy.ics")


@pytest.fixture(scope="module")
def utc_file() -> IcsAgenda:
    return load_ics_file(DATA / "agenda_utc.ics")


def _day(source: IcsAgenda, date: dt.date, tz: str = "Europe/Madrid") -> AgendaDay:
    return expand_day([source], date, tz, OBJECTS)


def test_daily_rrule_with_exdate_and_until(therapy: IcsAgenda) -> None:
    days_with_therapy = []
    for offset in range(-2, 16):
        date = dt.date(2025, 3, 24) + dt.timedelta(days=offset)
        if _day(therapy, date).activities:
            days_with_therapy.append(date.day if date.month == 3 else 100 + date.day)
    # 24..31 March except the EXDATE on the 27th, then 1..6 April: UNTIL is 08:00Z on the 6th, which
    # is exactly that day's 10:00 CEST occurrence (UNTIL is inclusive).
    assert days_with_therapy == [24, 25, 26, 28, 29, 30, 31, 101, 102, 103, 104, 105, 106]


def test_daily_therapy_keeps_local_time_across_dst(therapy: IcsAgenda) -> None:
    before = _day(therapy, dt.date(2025, 3, 28))  # CET, UTC+1
    dst_day = _day(therapy, dt.date(2025, 3, 30))  # clocks go forward at 02:00
    after = _day(therapy, dt.date(2025, 3, 31))  # CEST, UTC+2
    for day in (before, dst_day, after):
        (activity,) = day.activities
        assert (activity.start_s, activity.end_s) == (10 * H, 11.5 * H)
    # Same wall clock, different instants: 09:00 UTC before the change, 08:00 UTC after it.
    occ_before = therapy.occurrences(dt.date(2025, 3, 28), before.zone)[0]
    occ_after = therapy.occurrences(dt.date(2025, 3, 31), after.zone)[0]
    assert occ_before.start.astimezone(dt.UTC).hour == 9
    assert occ_after.start.astimezone(dt.UTC).hour == 8


def test_fields_follow_the_conventions(therapy: IcsAgenda) -> None:
    (activity,) = _day(therapy, dt.date(2025, 3, 25)).activities
    assert activity.id == "round_table-1000"
    assert activity.name == "Table therapy"
    assert activity.object == "round_table"
    assert activity.room == "occupational_therapy"
    assert activity.participants == ("Carmen", "José")
    assert activity.kind == "therapy"
    assert activity.state is ActivityState.SCHEDULED
    assert activity.source.endswith("agenda_daily_therapy.ics:22 UID=daily-therapy@centre.example")


def test_recurrence_id_override_moves_one_occurrence(therapy: IcsAgenda) -> None:
    (moved,) = _day(therapy, dt.date(2025, 4, 1)).activities
    assert (moved.start_s, moved.end_s) == (16 * H, 17.5 * H)
    assert moved.name == "Table therapy (afternoon)"
    # Not repeated in the override, so inherited from the series:
    assert moved.object == "round_table" and moved.participants == ("Carmen", "José")
    assert moved.source.endswith("agenda_daily_therapy.ics:38 UID=daily-therapy@centre.example")


def test_override_can_move_an_occurrence_to_another_day_or_cancel_it() -> None:
    text = "\n".join([
        "BEGIN:VCALENDAR", "VERSION:2.0", "PRODID:-//t//EN",
        "BEGIN:VEVENT", "UID:s", "DTSTART;TZID=Europe/Madrid:20250303T100000",
        "DURATION:PT1H", "RRULE:FREQ=DAILY;COUNT=5", "X-CHRONAV-OBJECT:tv", "SUMMARY:Game", "END:VEVENT",
        # the 4th moves to the 6th at 15:00; the 5th is cancelled (RECURRENCE-ID written in UTC)
        "BEGIN:VEVENT", "UID:s", "RECURRENCE-ID;TZID=Europe/Madrid:20250304T100000",
        "DTSTART;TZID=Europe/Madrid:20250306T150000", "DURATION:PT1H", "END:VEVENT",
        "BEGIN:VEVENT", "UID:s", "RECURRENCE-ID:20250305T090000Z", "STATUS:CANCELLED",
        "DTSTART;TZID=Europe/Madrid:20250305T100000", "DURATION:PT1H", "END:VEVENT",
        "END:VCALENDAR", ""])
    agenda = parse_ics(text, "inline.ics")
    starts = {d: [(a.start_s, a.state) for a in _day(agenda, dt.date(2025, 3, d)).activities]
              for d in range(3, 8)}
    assert starts[3] == [(10 * H, ActivityState.SCHEDULED)]
    assert starts[4] == []
    assert starts[5] == [(10 * H, ActivityState.CANCELLED)]
    assert starts[6] == [(10 * H, ActivityState.SCHEDULED), (15 * H, ActivityState.SCHEDULED)]
    assert starts[7] == [(10 * H, ActivityState.SCHEDULED)]  # COUNT=5 ends on the 7th


def test_utc_events_on_the_spring_forward_night(utc_file: IcsAgenda) -> None:
    day = _day(utc_file, dt.date(2025, 3, 30))
    by_id = {a.id: a for a in day.activities}
    # 00:30Z-01:30Z = 01:30 CET to 03:30 CEST: one real hour, two hours of wall clock.
    night = by_id["tv-0130"]
    assert (night.start_s, night.end_s) == (1.5 * H, 3.5 * H)
    game = by_id["tv-1100"]  # 09:00Z is 11:00 CEST
    assert (game.start_s, game.end_s) == (11 * H, 12 * H)
    assert game.participants == ("ana", "Luis, the volunteer")  # X-CHRONAV-PARTICIPANTS, escaped comma
    assert game.kind == "serious_game"


@pytest.mark.parametrize("end", ["DURATION:PT1H", "DTEND;TZID=Europe/Madrid:20250330T033000"])
def test_zoned_event_across_the_gap_lasts_its_real_length(end: str) -> None:
    text = "\n".join(["BEGIN:VCALENDAR", "VERSION:2.0", "PRODID:-//t//EN", "BEGIN:VEVENT", "UID:n",
                      "DTSTART;TZID=Europe/Madrid:20250330T013000", end, "LOCATION:tv",
                      "END:VEVENT", "END:VCALENDAR", ""])
    (night,) = _day(parse_ics(text, "n.ics"), dt.date(2025, 3, 30)).activities
    # One real hour from 01:30 CET ends at 03:30 CEST (02:00-03:00 does not exist that night).
    assert (night.start_s, night.end_s) == (1.5 * H, 3.5 * H)


def test_dtstart_is_an_occurrence_even_off_the_rule() -> None:
    # A Tuesday DTSTART with a Mondays-only rule: calendar apps show the Tuesday too.
    text = "\n".join(["BEGIN:VCALENDAR", "VERSION:2.0", "PRODID:-//t//EN", "BEGIN:VEVENT", "UID:m",
                      "DTSTART;TZID=Europe/Madrid:20261103T100000", "DURATION:PT1H",
                      "RRULE:FREQ=WEEKLY;BYDAY=MO", "LOCATION:tv", "END:VEVENT", "END:VCALENDAR", ""])
    agenda = parse_ics(text, "m.ics")
    days = [d for d in range(2, 11) if _day(agenda, dt.date(2026, 11, d)).activities]
    assert days == [3, 9]


def test_utc_event_in_the_repeated_autumn_hour_keeps_its_real_length(utc_file: IcsAgenda) -> None:
    (night,) = _day(utc_file, dt.date(2025, 10, 26)).activities
    # 00:30Z-01:30Z = 02:30 CEST to 02:30 CET: zero wall-clock length, so end = start + 1 h.
    assert (night.start_s, night.end_s) == (2.5 * H, 3.5 * H)


def test_cancelled_status_and_object_precedence(utc_file: IcsAgenda) -> None:
    day = _day(utc_file, dt.date(2025, 3, 30))
    (therapy,) = day.on_object("round_table")
    assert therapy.state is ActivityState.CANCELLED
    assert (therapy.start_s, therapy.end_s) == (12 * H, 14 * H)  # DURATION:PT2H from 10:00Z
    # X-CHRONAV-OBJECT wins over LOCATION (which here names the room)
    assert therapy.object == "round_table"
    assert day.windows()[[a.id for a in day.activities].index(therapy.id)].cancelled


def test_floating_time_is_the_centres_clock(utc_file: IcsAgenda) -> None:
    madrid = {a.name.split(" ")[0]: a for a in _day(utc_file, dt.date(2025, 3, 30)).activities}
    utc = {a.name.split(" ")[0]: a for a in _day(utc_file, dt.date(2025, 3, 30), "UTC").activities}
    assert madrid["Music"].start_s == utc["Music"].start_s == 17 * H
    assert madrid["Music"].participants == ("Rosa", "pablo@centre.example")  # ATTENDEE CN, else address
    assert utc["Serious"].start_s == 9 * H  # a UTC event moves with the centre's zone


def test_event_crossing_midnight_is_on_both_days(utc_file: IcsAgenda) -> None:
    late = "Late film (crosses midnight)"
    first = {a.name: a for a in _day(utc_file, dt.date(2025, 3, 30)).activities}[late]
    second = {a.name: a for a in _day(utc_file, dt.date(2025, 3, 31)).activities}[late]
    assert (first.start_s, first.end_s) == (23 * H, 25 * H)
    assert (second.start_s, second.end_s) == (-1 * H, 1 * H)
    assert second.id == "tv-p2300"


def test_custom_vtimezone_and_utc_exdate() -> None:
    text = "\r\n".join([
        "BEGIN:VCALENDAR", "VERSION:2.0", "PRODID:-//t//EN",
        "BEGIN:VTIMEZONE", "TZID:Centre time",
        "BEGIN:STANDARD", "DTSTART:19701025T030000", "RRULE:FREQ=YEARLY;BYMONTH=10;BYDAY=-1SU",
        "TZOFFSETFROM:+0200", "TZOFFSETTO:+0100", "END:STANDARD",
        "BEGIN:DAYLIGHT", "DTSTART:19700329T020000", "RRULE:FREQ=YEARLY;BYMONTH=3;BYDAY=-1SU",
        "TZOFFSETFROM:+0100", "TZOFFSETTO:+0200", "END:DAYLIGHT", "END:VTIMEZONE",
        "BEGIN:VEVENT", "UID:w", "DTSTART;TZID=Centre time:20250328T093000",
        "DTEND;TZID=Centre time:20250328T100000", "RRULE:FREQ=DAILY;UNTIL=20250402",
        "EXDATE:20250331T073000Z", "LOCATION:tv", "END:VEVENT", "END:VCALENDAR", ""])
    agenda = parse_ics(text.encode(), "custom.ics")
    starts = [[a.start_s for a in _day(agenda, dt.date(2025, 3, 28) + dt.timedelta(days=i)).activities]
              for i in range(7)]
    # 28, 29, 30 March at 09:30; the 31st removed by a UTC EXDATE (07:30Z = 09:30 CEST); 1, 2 April
    # (a DATE UNTIL includes its day); nothing on the 3rd.
    assert starts == [[9.5 * H], [9.5 * H], [9.5 * H], [], [9.5 * H], [9.5 * H], []]


def test_rdate_adds_occurrences_and_periods_bring_their_own_end() -> None:
    text = "\n".join(["BEGIN:VCALENDAR", "VERSION:2.0", "PRODID:-//t//EN", "BEGIN:VEVENT", "UID:r",
                      "DTSTART;TZID=Europe/Madrid:20261102T100000", "DURATION:PT1H",
                      "RDATE;TZID=Europe/Madrid:20261104T170000",
                      "RDATE;VALUE=PERIOD:20261105T080000Z/PT3H", "LOCATION:tv",
                      "END:VEVENT", "END:VCALENDAR", ""])
    agenda = parse_ics(text, "r.ics")
    spans = {d: [(a.start_s, a.end_s) for a in _day(agenda, dt.date(2026, 11, d)).activities]
             for d in range(2, 7)}
    assert spans == {2: [(10 * H, 11 * H)], 3: [], 4: [(17 * H, 18 * H)], 5: [(9 * H, 12 * H)], 6: []}


def test_all_day_event_fills_the_local_day() -> None:
    text = "\n".join(["BEGIN:VCALENDAR", "VERSION:2.0", "PRODID:-//t//EN", "BEGIN:VEVENT", "UID:a",
                      "DTSTART;VALUE=DATE:20251026", "X-CHRONAV-OBJECT:round_table", "SUMMARY:Open day",
                      "END:VEVENT", "END:VCALENDAR", ""])
    (activity,) = _day(parse_ics(text, "a.ics"), dt.date(2025, 10, 26)).activities  # a 25-hour day
    assert (activity.start_s, activity.end_s) == (0.0, 24 * H)
    assert _day(parse_ics(text, "a.ics"), dt.date(2025, 10, 27)).activities == ()


def test_bad_file_reports_every_problem_with_line_and_uid() -> None:
    with pytest.raises(AgendaSourceError) as info:
        load_ics_file(DATA / "agenda_bad.ics")
    problems = {p.line: p.message for p in info.value.problems}
    assert set(problems) == {4, 10, 17, 24, 31, 39, 45}  # the correct event at line 52 is not blamed
    assert all(p.file.endswith("agenda_bad.ics") for p in info.value.problems)
    assert problems[4].startswith("UID=no-object@centre.example: no object: set X-CHRONAV-OBJECT")
    assert "UID=backwards@centre.example: the end is not after the start" in problems[10]
    assert "DTEND" in problems[17] and "half past twelve" in problems[17]
    assert "unknown time zone 'Centre Local Time'" in problems[24]
    assert "RRULE" in problems[31] and "SOMETIMES" in problems[31]
    assert "no DTEND or DURATION" in problems[39]
    assert "no DTSTART" in problems[45]
    assert str(info.value).splitlines()[0].endswith(
        "agenda_bad.ics:4: UID=no-object@centre.example: no object: set X-CHRONAV-OBJECT (or LOCATION) "
        "to the name of the object the activity uses, e.g. X-CHRONAV-OBJECT:tv")


def test_unknown_object_names_the_event_and_suggests_a_name(therapy: IcsAgenda) -> None:
    with pytest.raises(AgendaValidationError) as info:
        expand_day([therapy], dt.date(2025, 3, 25), "Europe/Madrid", {"tv", "round_tabel"})
    message = str(info.value)
    assert "'round_table-1000'" in message and "agenda_daily_therapy.ics:22" in message
    assert "no object named 'round_table'" in message and "did you mean 'round_tabel'?" in message


def test_not_an_ics_file_and_duplicate_uids() -> None:
    with pytest.raises(AgendaSourceError, match="not a valid iCalendar"):
        parse_ics("hello world\n", "notes.ics")
    event = ["BEGIN:VEVENT", "UID:same", "DTSTART:20250330T100000Z", "DURATION:PT1H", "LOCATION:tv",
             "END:VEVENT"]
    text = "\n".join(["BEGIN:VCALENDAR", "VERSION:2.0", *event, *event, "END:VCALENDAR", ""])
    with pytest.raises(AgendaSourceError, match=r"dup.ics:9: UID=same: a second event .*first at line 3"):
        parse_ics(text, "dup.ics")
    with pytest.raises(AgendaSourceError, match="no_such_agenda.ics: no such file"):
        load_ics_file(DATA / "no_such_agenda.ics")
    with pytest.raises(AgendaSourceError, match="not UTF-8 text"):
        parse_ics(b"\xff\xfeB\x00E\x00", "utf16.ics")
    with pytest.raises(AgendaSourceError, match="END:VCALENDAR"):
        parse_ics("BEGIN:VCALENDAR\nVERSION:2.0\n", "cut.ics")


def test_byte_order_mark_is_accepted() -> None:
    data = "\ufeff" + (DATA / "agenda_utc.ics").read_text(encoding="utf-8")
    agenda = parse_ics(data.encode("utf-8"), "bom.ics")
    assert agenda.events[0].line == 4


def test_staff_sample_matches_the_icra_use_case() -> None:
    (agenda,) = load_agenda_file(SCENES / "sample_agenda.ics")
    wednesday = expand_day([agenda], dt.date(2026, 11, 25), "Europe/Madrid", OBJECTS)
    assert [(a.id, a.object, a.start_s, a.end_s) for a in wednesday.activities] == [
        ("tv-1100", "tv", 11 * H, 12 * H), ("round_table-1200", "round_table", 12 * H, 14 * H)]
    assert wednesday.get("round_table-1200").participants == ("senior_1", "senior_2", "therapist")
    saturday = expand_day([agenda], dt.date(2026, 11, 28), "Europe/Madrid", OBJECTS)
    assert [a.object for a in saturday.activities] == ["round_table"]  # the game is weekdays only
    holiday = expand_day([agenda], dt.date(2026, 12, 8), "Europe/Madrid", OBJECTS)
    assert [a.object for a in holiday.activities] == ["tv"]  # EXDATE
    friday = expand_day([agenda], dt.date(2026, 11, 27), "Europe/Madrid", OBJECTS)
    assert friday.get("tv-1600").start_s == 16 * H  # the one-off move

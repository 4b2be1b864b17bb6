"""Output piped or at 80 columns stays readable (issue 39, point 3).

rich falls back to 80 columns whenever stdout is not a terminal; its tables then folded names
mid-word (``therapis``/``t_eva``), `dsr dump` took thousands of lines with times as ``3.24e+04``
and `chaos` cut its columns.  Each test prints through the command's own code at 80 columns, not
on a terminal, and checks that known names stay whole and that the line count is sane.
"""

from __future__ import annotations

import re
from io import StringIO
from pathlib import Path
from typing import Any

from typer.testing import CliRunner

from scenes.clock import format_clock
from tests.support import REPO_ROOT
from tools import agenda as agenda_tool
from tools.cli import app
from tools.system.dsr_dump import attr_text, dump_lines

WIDTH = 80
PIPED = {"COLUMNS": str(WIDTH), "TERM": "dumb"}

# Long names as staff write them: a cell of 10 characters folds each of them mid-word.
PEOPLE = ["therapist_eva", "nurse_marta", "resident_alberto", "resident_carmen", "visitor_lucia",
          "resident_francisco", "resident_dolores", "resident_josefina"]


def _lines(text: str) -> list[str]:
    return [line for line in text.splitlines() if line.strip()]


def _assert_fits(lines: list[str], width: int = WIDTH) -> None:
    too_long = [line for line in lines if len(line) > width]
    assert not too_long, too_long


def test_format_clock_always_has_seconds() -> None:
    assert format_clock(11 * 3600) == "11:00:00"
    assert format_clock(11 * 3600 + 30) == "11:00:30"
    assert format_clock(32400.4) == "09:00:00"


def _agenda_data(count: int) -> dict[str, Any]:
    activities = [{"id": f"table_therapy_{i}", "name": f"Table therapy number {i}", "object": "round_table",
                   "start": format_clock(9 * 3600 + i * 1800), "end": format_clock(9 * 3600 + i * 1800 + 1500),
                   "state": "upcoming", "participants": PEOPLE, "object_R": 1.5} for i in range(count)]
    return {"graph": "center_day_20261204", "now": "09:05:00", "activities": activities,
            "objects": [{"name": "round_table", "R": 1.5, "band": "green", "active": False}]}


def test_agenda_list_piped_keeps_names_whole() -> None:
    out = StringIO()          # not a terminal: what `chronav agenda list | less` writes
    agenda_tool.print_snapshot(_agenda_data(10), out)
    lines = _lines(out.getvalue())
    _assert_fits(lines)
    words = set(re.findall(r"[A-Za-z0-9_]+", out.getvalue()))
    assert set(PEOPLE) <= words, "a participant's name was split"
    assert {f"table_therapy_{i}" for i in range(10)} <= words
    assert lines[0] == "agenda of center_day_20261204 at 09:05:00: 10 activities"
    assert len(lines) <= 4 * 10 + 3, f"{len(lines)} lines for 10 activities"
    assert "09:30:00-09:55:00 upcoming: table_therapy_1 (Table therapy number 1)" in out.getvalue()


def test_agenda_list_counts_one_activity() -> None:
    out = StringIO()
    agenda_tool.print_snapshot(_agenda_data(1), out)
    assert out.getvalue().splitlines()[0].endswith(": 1 activity")


def test_dsr_dump_groups_by_type_one_line_per_node() -> None:
    from agents.world.offline import graph_at
    from agents.world.scene_world import load_world

    world = load_world(REPO_ROOT / "scenes" / "center_day.yaml")
    graph = graph_at(world, 9 * 3600 + 30 * 60)
    lines = dump_lines(graph, WIDTH, all_attrs=False)
    _assert_fits(lines)
    types = {n.type for n in graph.nodes()}
    sources = {(e.type, e.src) for e in graph.edges() if e.type != "RT"}
    # A title, a heading and one line per node, one line per edge type and per edge source (no
    # edge source has so many targets that its line wraps here): nothing folded.
    assert len(lines) == 1 + len(types) + len(graph) + len({e.type for e in graph.edges()}) + len(sources)
    assert len(lines) < 2 * len(graph) + 50, len(lines)
    assert "  tv @(4.00, 9.85) kind=tv, R=3.50, R_band=3, active=True" in lines
    assert not any("e+0" in line for line in lines)
    assert any(line.startswith("  clock now_s=09:30:00, mode=idle") for line in lines), lines[:20]
    assert "person (" in "\n".join(lines) and "activity (" in "\n".join(lines)
    every = dump_lines(graph, WIDTH, all_attrs=True)
    _assert_fits([line for line in every if " " in line.strip()])    # only an unbreakable token may overflow
    assert len(every) >= len(lines) and "polygon_x=[" in "\n".join(every)


def test_attr_text_prints_times_of_day_and_plain_floats() -> None:
    assert attr_text("now_s", 32400.0) == "now_s=09:00:00"
    assert attr_text("wall_s", 1.7e9) == "wall_s=1700000000.00"
    assert attr_text("R", 3.37123) == "R=3.37"
    assert attr_text("laser_ranges", [1.0] * 360) == "laser_ranges=[1.00, 1.00, 1.00, ... 360 items]"


def _chaos_summary() -> dict[str, Any]:
    faults = [{"what": f"kill {agent}", "at_wall_s": 3.25, "at_sim_s": 9 * 3600 + 1800 + i, "mission": "m0930",
               "recovered_s": 1.2, "converged_s": 1.6, "note": "restarted by the supervisor, rejoined the graph"}
              for i, agent in enumerate(["social_navigation", "human_observer", "object_recognition"])]
    return {"scene": "icra_usecase", "ok": True, "faults": faults, "missions_completed": 4, "missions_total": 4,
            "faults_injected": 3, "faults_planned": 3, "convergence_max_s": 1.6, "writes_lost": 0, "lost": [],
            "trust": {"refusals_total": 0, "refusals": {}, "unproven_claims_served": [], "router_acl_denied": 0}}


class _Report:
    ok = True

    def summary(self) -> dict[str, Any]:
        return _chaos_summary()


def test_chaos_piped_keeps_every_column(monkeypatch: Any, tmp_path: Path) -> None:
    import tools.chaos.command as chaos_command

    monkeypatch.setattr(chaos_command, "run_chaos", lambda *args, **kwargs: _Report())
    result = CliRunner().invoke(app, ["chaos", "icra_usecase", "--runs-dir", str(tmp_path)], env=PIPED)
    assert result.exit_code == 0, result.output
    lines = _lines(result.stdout)
    _assert_fits(lines)
    text = result.stdout
    for agent in ("social_navigation", "human_observer", "object_recognition"):
        assert f"kill {agent} at 3.25 s wall (sim 09:30:0" in " ".join(text.split())
    assert "restarted by the supervisor, rejoined the graph" in " ".join(text.split())
    assert len(lines) <= 3 * 3 + 5


def test_dsr_dump_follow_lines_print_times_of_day() -> None:
    from dsr import DSRGraph
    from tools.system.dsr_dump import _event_text

    graph = DSRGraph("follow")
    clock = graph.insert_node(type="clock", name="clock", attrs={"now_s": 32400.0, "mode": "idle"})
    assert _event_text(graph, "node_updated", (clock, ["now_s"])) == f"~ node clock (clock, {clock.id}) now_s=09:00:00"
    assert _event_text(graph, "node_added", (clock,)).endswith("mode=idle, now_s=09:00:00")


def test_dsr_stats_piped_keeps_every_counter(capsys: Any, monkeypatch: Any) -> None:
    from tools.system.dsr_dump import _print_stats

    monkeypatch.setenv("COLUMNS", str(WIDTH))
    report = {"nodes": 55, "tombstones": 3, "stats": {"received": 1200, "applied": 1190, "published": 300,
                                                      "rejects": {"policy": 2}, "rejected_policy": 2, "deferred": 0,
                                                      "syncs": 4, "fetches_postponed": 1, "compacted": 9}}
    agents = ["social_navigation", "human_observer", "object_recognition"]
    _print_stats("center_day_run", {"members": {a: report for a in agents}, "router": None})
    lines = _lines(capsys.readouterr().out)
    _assert_fits(lines)
    assert lines[0] == "DSR graph 'center_day_run': 3 members"
    text = " ".join(" ".join(lines).split())
    for agent in agents:
        assert (f"{agent}: nodes 55, received 1200, applied 1190, published 300, refused policy=2, policy 2, "
                f"deferred 0, fetches 4 (held back 1), tombstones 3, compacted 9") in text

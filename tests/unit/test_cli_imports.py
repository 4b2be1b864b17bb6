"""What a fresh `chronav` process imports (issue 17: `chronav path` on a 2,000 x 1,200 cell map
in under 1 s, loading included, when a process that only loads the A* kernel from numba's cache
already takes most of that; docs/maps.md, Scale).

Why a subprocess: imports are paid once per process, and pytest has imported everything already.
The child runs the console script's ``main()`` and, at exit, writes the names in ``sys.modules``.
A package a command does not need (the live system's zenoh and rerun, the calendar parser, the
symbolic planner's networkx, dask) showing up there is a regression of the command's start-up
time.  No time is asserted: tools/bench/bench_planner.py measures ``path_cli_s_map``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from tests.support import REPO_ROOT

# Runs `chronav ARGS` as the console script does; argv[1] is where to write the module names.
PROBE = """
import atexit, json, sys
out = sys.argv[1]
def dump():
    with open(out, "w", encoding="utf-8") as f:
        json.dump(sorted(sys.modules), f)
atexit.register(dump)  # registered first, so it runs after every other exit handler
sys.argv = ["chronav", *sys.argv[2:]]
from tools.cli import main
main()
"""

# Never needed to plan one path offline: the live system (zenoh, rerun), the symbolic planner
# (grammar, lark, networkx), reports and studies (dask, pandas, matplotlib), process tools (psutil).
NEVER_FOR_PATH = ("zenoh", "rerun", "rerun_cli", "networkx", "grammar", "lark", "dask", "pandas", "matplotlib",
                  "psutil")
CALENDAR = ("icalendar", "recurring_ical_events", "dateutil")


def imported_by(tmp_path: Path, *args: str) -> tuple[set[str], str]:
    """The modules (full dotted names) a fresh `chronav ARGS` process held at exit, and its stdout."""
    out = tmp_path / "modules.json"
    env = dict(os.environ, PYTHONPATH=str(REPO_ROOT))
    proc = subprocess.run([sys.executable, "-c", PROBE, str(out), *args], cwd=REPO_ROOT, env=env,
                          capture_output=True, text=True, timeout=180)
    assert proc.returncode == 0, proc.stderr
    return set(json.loads(out.read_text(encoding="utf-8"))), proc.stdout


def packages(modules: set[str]) -> set[str]:
    return {name.split(".")[0] for name in modules}


def test_path_on_a_map_imports_only_the_planner(tmp_path: Path) -> None:
    modules, stdout = imported_by(tmp_path, "path", "map_ward", "--at", "10:05", "--from", "3,8",
                                  "--to", "28,12", "--json")
    assert json.loads(stdout)["length_m"] > 20.0  # it did plan, through the numba search
    assert "numba" in packages(modules)
    unneeded = sorted(packages(modules) & {*NEVER_FOR_PATH, *CALENDAR})
    assert not unneeded, (f"`chronav path` imports {unneeded}, which it does not need: import them inside the "
                          "functions that use them (as agents/lib/agenda/ics_source.py does icalendar)")
    # map_ward's people stay or follow waypoints: no walking-route graph, so no scipy.sparse
    # (scipy.linalg itself comes with numba's first compiled call).
    assert not sorted(m for m in modules if m.startswith("scipy.sparse"))


def test_the_calendar_parser_loads_only_for_an_ics_agenda(tmp_path: Path) -> None:
    scene = tmp_path / "icra_with_ics.yaml"
    scene.write_text((REPO_ROOT / "scenes" / "icra_usecase.yaml").read_text(encoding="utf-8")
                     + f"\nagenda_file: {REPO_ROOT / 'scenes' / 'sample_agenda.ics'}\n", encoding="utf-8")
    modules, stdout = imported_by(tmp_path, "path", str(scene), "--at", "11:15", "--from", "12,2", "--to", "1,1",
                                  "--json")
    assert json.loads(stdout)["objects"]["tv"]["active"]
    assert {"icalendar", "recurring_ical_events"} <= packages(modules)
    assert not sorted(packages(modules) & set(NEVER_FOR_PATH))


#: what every process imports at its end (agents/runtime/exit_guard.py): the standard library only,
#: under two packages whose ``__init__`` is a docstring
EXIT_GUARD = {"agents", "agents.runtime", "agents.runtime.exit_guard"}


def test_help_imports_no_numerics(tmp_path: Path) -> None:
    modules, stdout = imported_by(tmp_path, "--help")
    assert "path" in stdout
    assert EXIT_GUARD <= modules                     # the guard ran
    modules -= EXIT_GUARD
    assert not sorted(packages(modules) & {"numpy", "numba", "scipy", "shapely", "pydantic", "yaml", "agents",
                                           "dsr", "scenes", "grammar", *NEVER_FOR_PATH, *CALENDAR})

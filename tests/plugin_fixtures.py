"""A throw-away installed package of plug-ins for the tests: a ``*.dist-info`` directory with
``entry_points.txt`` and a module, on a directory the test puts on ``sys.path`` or PYTHONPATH.

Why a real distribution and not a patched registry: importlib.metadata finds it exactly as it
finds a package installed by pip, so the tests exercise the path a researcher's package takes.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

BROKEN_MODULE = '''"""Deliberately broken chronav plug-ins for the tests."""
import math

import numpy as np

from agents.lib.control.elastic_band_controller import ElasticBandController
from agents.lib.control.protocol import ControlCommand
from agents.lib.planning.planners import BaselinePlanner
from agents.lib.planning.search import Path


class NanController:
    """Answers NaN: the navigation must refuse it."""

    def __init__(self, limits):
        self.limits = limits

    def reset(self):
        pass

    def command(self, control_input):
        return ControlCommand(vx=math.nan, vy=0.0, omega=0.0, reached=False, distance_to_goal_m=1.0)


class RaisingController(NanController):
    """Raises in the middle of a run."""

    def command(self, control_input):
        raise RuntimeError("boom")


class OffMapPlanner(BaselinePlanner):
    """Plans like baseline, then returns a path 100 m off the map."""

    def plan(self, smap, request):
        path = super().plan(smap, request)
        points = path.points_m.copy()
        points[len(points) // 2] += 100.0
        return Path(cells=path.cells, points_m=points, cost=path.cost, expanded=path.expanded)


class NotAController:
    """Has no command(): its factory breaks the protocol."""

    def __init__(self, limits):
        pass


NOT_A_FACTORY = 42

SEEN = []


class RecordingController(ElasticBandController):
    """The elastic band, keeping every ControlInput it is given (what the agent shows a controller)."""

    reads_people = True

    def command(self, control_input):
        SEEN.append(control_input)
        return super().command(control_input)


class RaisingMetric:
    """Raises on every mission."""

    def measure(self, run):
        raise ValueError("no such column")


class ClashingMetric:
    """Gives a column chronav's catalogue gives too, and one of its own."""

    def measure(self, run):
        return {"duration_s": -1.0, "clash_own": 2.0}
'''

DEFAULT_ENTRIES: dict[str, dict[str, str]] = {
    "chronav.controllers": {"nan_ctrl": "chronav_test_plugins:NanController",
                            "recording_ctrl": "chronav_test_plugins:RecordingController",
                            "raising_ctrl": "chronav_test_plugins:RaisingController",
                            "no_command": "chronav_test_plugins:NotAController",
                            "missing_module": "chronav_no_such_module:Factory"},
    "chronav.planners": {"off_map": "chronav_test_plugins:OffMapPlanner",
                         "not_a_factory": "chronav_test_plugins:NOT_A_FACTORY",
                         "social": "chronav_test_plugins:OffMapPlanner"},     # chronav's name, taken
    "chronav.metrics": {"raising_metric": "chronav_test_plugins:RaisingMetric",
                        "zz_clash": "chronav_test_plugins:ClashingMetric"},
}


def install_fake_plugins(root: Path, entries: Mapping[str, Mapping[str, str]] | None = None,
                         name: str = "chronav-test-plugins", module: str = BROKEN_MODULE,
                         module_name: str = "chronav_test_plugins") -> Path:
    """Write the package under ``root`` (put ``root`` on sys.path or PYTHONPATH) and return ``root``.
    Another ``module`` needs another ``module_name``: a test session imports each name once."""
    root.mkdir(parents=True, exist_ok=True)
    (root / f"{module_name}.py").write_text(module, encoding="utf-8")
    info = root / f"{name.replace('-', '_')}-0.1.dist-info"
    info.mkdir(exist_ok=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1\n", encoding="utf-8")
    lines = []
    for group, items in (entries or DEFAULT_ENTRIES).items():
        lines.append(f"[{group}]")
        lines += [f"{key} = {value}" for key, value in items.items()]
        lines.append("")
    (info / "entry_points.txt").write_text("\n".join(lines), encoding="utf-8")
    return root

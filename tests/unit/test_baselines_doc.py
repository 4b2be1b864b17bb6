"""docs/baselines.md: each navground behaviour's parameters exactly as the models define them, and
the measured distances of its head-on table as the controllers give them today."""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from agents.lib.control import controllers
from agents.lib.control.navground_behaviours import PARAMS_BY_BEHAVIOUR, NavgroundParams, parameter_table
from tests.unit.test_navground_controllers import LIMITS, OMNI, STRAIGHT, drive

DOC = Path(__file__).resolve().parents[2] / "docs" / "baselines.md"


@pytest.mark.parametrize("params", [NavgroundParams, *PARAMS_BY_BEHAVIOUR.values()], ids=lambda p: p.__name__)
def test_the_parameter_tables_match_the_models(params: type[NavgroundParams]) -> None:
    text = DOC.read_text(encoding="utf-8")
    assert "## The behaviours and their parameters" in text
    assert f"(`{params.__name__}`)" in text
    assert parameter_table(params) in text, (
        f"docs/baselines.md: the table of {params.__name__} is out of date; regenerate it with "
        f"agents.lib.control.navground_behaviours.parameter_table")


def test_every_parameter_names_its_source() -> None:
    models: list[type[NavgroundParams]] = [NavgroundParams, *PARAMS_BY_BEHAVIOUR.values()]
    for params in models:
        for name, info in params.model_fields.items():
            assert info.description, f"{params.__name__}.{name} has no description"
            assert any(word in info.description for word in ("navground", "paper", "chronav", "RVO2", "HRVO")), \
                f"{params.__name__}.{name}: the description does not say where the default comes from"


def _person(speed: float, offset: float) -> Callable[[float], np.ndarray]:
    return lambda t: np.array([[6.0 - speed * t, offset, -speed, 0.0, 0.3]])


def test_the_head_on_table_is_what_the_controllers_do() -> None:
    """Each row of the doc's head-on table, run again: the least centre distance to the person."""
    rows = re.findall(r"^\| (\d\.\d) m/s, (0\.2 m off|exactly on) the line \| (differential|omni) \| (.+) \|$",
                      DOC.read_text(encoding="utf-8"), flags=re.MULTILINE)
    assert len(rows) == 5
    for speed, where, drive_name, cells in rows:
        limits = LIMITS if drive_name == "differential" else OMNI
        person = _person(float(speed), 0.2 if where.startswith("0.2") else 0.0)
        documented = [float(cell.strip("* ")) for cell in cells.split("|")]
        for name, value in zip(("orca", "hrvo", "hl", "social_force"), documented, strict=True):
            poses, _, seen = drive(controllers.controller(name, limits), STRAIGHT, limits, people=person)
            closest = min(math.hypot(p[0] - c[0, 0], p[1] - c[0, 1]) for p, c in zip(poses, seen, strict=False))
            assert closest == pytest.approx(value, abs=0.006), (
                f"docs/baselines.md: {name}, {speed} m/s {where} the line, {drive_name}: documented {value}, "
                f"measured {closest:.2f}")

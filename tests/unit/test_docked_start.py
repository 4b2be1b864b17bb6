"""A robot may start where a real one docks (issue 27): collision-free but inside the planning margin.

icra_usecase's robot (radius 0.3 m, margin 0.15 m) moved to 0.35 m from the east wall (x = 14):
`chronav scene check` accepts the scene with a warning (it refused it before), and a plan from there
leaves the margin by the cheapest way out - straight off the wall, as from a charging dock - then
goes on as usual.  A pose in collision (0.2 m from the wall) is still refused.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from typer.testing import CliRunner

from scenes.loader import SCENES_DIR
from tools.cli import app


def docked(tmp_path: Path, x: float) -> Path:
    text = (SCENES_DIR / "icra_usecase.yaml").read_text().replace("pose: [12.0, 2.0, 3.1416]", f"pose: [{x}, 2.0, 0.0]")
    path = tmp_path / "docked.yaml"
    path.write_text(text)
    return path


def test_a_docked_start_is_accepted_with_a_warning_and_left_the_cheapest_way(tmp_path: Path) -> None:
    scene = docked(tmp_path, 13.65)
    result = CliRunner().invoke(app, ["scene", "check", str(scene)])
    assert result.exit_code == 0, result.output
    assert "warning: robot.pose" in result.output and "planning margin" in result.output
    plan = CliRunner().invoke(app, ["path", str(scene), "--at", "09:30", "--from", "13.65,2.0", "--to", "11.0,4.0",
                                    "--json"])
    assert plan.exit_code == 0, plan.output
    points = json.loads(plan.stdout)["points"]
    assert points[0] == [13.65, 2.0]
    (x0, y0), (x1, y1) = points[0], points[1]
    assert x1 < x0 and abs(y1 - y0) <= 0.05 + 1e-9, "straight off the east wall"
    assert 14.0 - x1 >= 0.45 - 0.05, "out of the margin (radius 0.3 + 0.15)"
    assert math.hypot(x1 - x0, y1 - y0) <= 0.15, "by the shortest way"


def test_a_start_in_collision_is_still_refused(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["scene", "check", str(docked(tmp_path, 13.8))])
    assert result.exit_code == 1 and "robot" in result.output

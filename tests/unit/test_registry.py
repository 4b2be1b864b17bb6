"""The extension registry (agents/lib/registry.py) and what the kinds make of it: unknown names,
refused plug-ins, checked answers, the cache.  The broken plug-ins are a real installed
distribution on sys.path (tests/plugin_fixtures.py), found as pip-installed ones are."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agents.lib import registry
from agents.lib.control import controllers
from agents.lib.control.protocol import ControlInput, RobotLimits
from agents.lib.planning.plan import PlannerFailed, plan
from agents.world.offline import SceneMaps
from tests.plugin_fixtures import install_fake_plugins
from tests.support import REPO_ROOT

TINY = REPO_ROOT / "tests" / "data" / "eval_tiny.yaml"
LIMITS = RobotLimits(radius_m=0.3, max_speed_mps=0.6, max_angular_speed_radps=1.2)


@pytest.fixture
def broken(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(install_fake_plugins(tmp_path / "site")))
    registry.clear()
    yield
    registry.clear()


def test_chronav_registers_its_own_like_any_package() -> None:
    planners = registry.extensions("planner")
    assert {"social", "departure", "static", "baseline", "inflation"} <= set(planners)
    assert planners["social"].package == "chronav" and planners["social"].target.endswith(":SocialPlanner")
    assert registry.extensions("controller")["elastic_band"].package == "chronav"


def test_unknown_name_lists_the_known_ones_and_their_packages(broken) -> None:
    with pytest.raises(registry.UnknownExtension) as exc:
        registry.entry("controller", "orca_typo")
    assert "unknown controller 'orca_typo'" in str(exc.value)
    assert "elastic_band (chronav)" in str(exc.value) and "nan_ctrl (chronav-test-plugins)" in str(exc.value)


def test_a_plugin_that_fails_to_import_or_breaks_its_protocol_is_refused_and_the_rest_load(broken) -> None:
    good, refused = registry.load_all("controller", registry.check_callable)
    assert {"elastic_band", "nan_ctrl"} <= set(good)
    reasons = {r.name: str(r) for r in refused}
    assert "missing_module" in reasons
    assert "package 'chronav-test-plugins'" in reasons["missing_module"]
    assert "cannot import chronav_no_such_module:Factory: ModuleNotFoundError" in reasons["missing_module"]
    with pytest.raises(registry.RefusedExtension, match="without reset\\(\\) and command\\(\\)"):
        controllers.controller("no_command", LIMITS)
    with pytest.raises(registry.RefusedExtension, match="names a int, not a factory"):
        registry.load("planner", "not_a_factory", registry.check_callable)


def test_nan_and_raising_controllers_are_refused_naming_them(broken) -> None:
    control_input = ControlInput(pose=(0.0, 0.0, 0.0), velocity=(0.0, 0.0, 0.0), path=np.array([[0.0, 0], [1, 0]]),
                                 goal_theta=None, limits=LIMITS, dt_s=0.1)
    with pytest.raises(controllers.ControllerFailed,
                       match="controller 'nan_ctrl' from package 'chronav-test-plugins' failed: returned vx = nan"):
        controllers.command(controllers.controller("nan_ctrl", LIMITS), "nan_ctrl", control_input)
    with pytest.raises(controllers.ControllerFailed, match="raised RuntimeError: boom"):
        controllers.command(controllers.controller("raising_ctrl", LIMITS), "raising_ctrl", control_input)
    good = controllers.command(controllers.controller("elastic_band", LIMITS), "elastic_band", control_input)
    assert math.isfinite(good.vx) and good.vx >= 0.0


def test_a_path_off_the_map_is_refused_naming_the_planner(broken) -> None:
    smap = SceneMaps.load(TINY).at(10 * 3600.0)
    with pytest.raises(PlannerFailed, match="planner 'off_map' from package 'chronav-test-plugins' failed: "
                                            "returned a path off the map"):
        plan(smap, (0.8, 1.2), (5.2, 1.2), planner="off_map")
    assert plan(smap, (0.8, 1.2), (5.2, 1.2), planner="baseline").length_m > 0


def test_lookups_are_cached() -> None:
    """The metadata is scanned once per kind and a factory imported once (bench: registry_*)."""
    first = registry.extensions("planner")
    assert registry.extensions("planner") is first
    assert registry.load("planner", "social") is registry.load("planner", "social")


def test_launch_and_path_refuse_a_broken_controller_at_start(broken) -> None:
    from typer.testing import CliRunner

    from tools.cli import app

    for args in (["launch", str(TINY), "--in-process", "--controller", "no_command"],
                 ["path", str(TINY), "--at", "10:01", "--from", "0.8,1.2", "--to", "5.2,1.2",
                  "--controller", "no_command"]):
        result = CliRunner().invoke(app, args)
        words = " ".join(result.output.replace("│", " ").split())
        assert result.exit_code == 2, result.output
        assert "controller plug-in 'no_command' from package 'chronav-test-plugins' refused" in words


def test_path_drives_a_controller_offline_and_reports_a_refusal(broken) -> None:
    import json

    from typer.testing import CliRunner

    from tools.cli import app

    base = ["path", str(TINY), "--at", "10:01", "--from", "0.8,1.2", "--to", "5.2,1.2", "--json", "--controller"]
    good = CliRunner().invoke(app, [*base, "elastic_band"])
    driven = json.loads(good.stdout)["controller"]
    assert good.exit_code == 0 and driven["reached"] and driven["refused"] is None
    assert abs(driven["points"][-1][0] - 5.2) < 0.2 and abs(driven["points"][-1][1] - 1.2) < 0.2
    assert driven["metrics"]["d_min_person_m"]["resident"] > 0.5       # measured on what it drove
    assert sum(driven["metrics"]["psi_percent"].values()) == pytest.approx(100.0)
    bad = CliRunner().invoke(app, [*base, "raising_ctrl"])
    assert bad.exit_code == 1
    assert "raised RuntimeError: boom" in json.loads(bad.stdout)["controller"]["refused"]


def test_plugins_lists_every_extension_and_says_why_one_is_refused(broken) -> None:
    import json

    from typer.testing import CliRunner

    from tools.cli import app

    result = CliRunner().invoke(app, ["plugins", "--json"])
    assert result.exit_code == 0, result.output
    listed = json.loads(result.stdout)
    rows: dict = {}
    for r in listed["plugins"]:
        rows.setdefault((r["kind"], r["name"]), r)     # the used entry first, then a shadowed one
    social = rows[("planner", "social")]
    assert (social["package"], social["status"]) == ("chronav", "ok")
    assert social["summary"].startswith("People's zones + interaction spaces priced by R(t) at arrival")
    assert rows[("controller", "elastic_band")]["status"] == "ok"
    assert {("predictor", "chronav"), ("predictor", "constant_velocity"), ("metric", "chronav")} <= set(rows)
    nan = rows[("controller", "nan_ctrl")]
    assert (nan["package"], nan["version"], nan["status"]) == ("chronav-test-plugins", "0.1", "ok")
    assert nan["summary"] == "Answers NaN: the navigation must refuse it."
    missing = rows[("controller", "missing_module")]
    assert missing["status"] == "refused" and "ModuleNotFoundError" in missing["reason"]
    assert rows[("controller", "no_command")]["reason"].endswith("without reset() and command()")
    assert listed["refused"] == 4    # and the test package's "social", a name chronav keeps
    assert "controller plug-in 'missing_module' from package 'chronav-test-plugins' refused" in result.stderr
    table = CliRunner().invoke(app, ["plugins"])
    assert table.exit_code == 0 and "REFUSED" in table.stdout and "nan_ctrl" in table.stdout
    # piped (as here): one line per plug-in, names and packages whole, never folded inside a table cell
    assert "\ncontroller nan_ctrl (chronav-test-plugins " in table.stdout
    assert "\ncontroller elastic_band (chronav " in table.stdout


def test_a_taken_name_keeps_its_first_package_and_a_failing_metric_is_reported(broken, tmp_path) -> None:
    from agents.lib.metrics.registered import MissionRun, measure_all
    from tools.plugins_cli import inventory

    assert registry.entry("planner", "social").package == "chronav"      # chronav keeps its names
    shadowed = [r for r in inventory() if r["name"] == "social" and r["package"] == "chronav-test-plugins"]
    assert shadowed and shadowed[0]["reason"] == "the name is taken by package 'chronav'"
    trajectory = np.array([[0.0, 0.8, 1.2, 0.0], [10.0, 5.2, 1.2, 0.0]])
    csv = tmp_path / "m.csv"
    csv.write_text("t,x,y,theta\n0,0.8,1.2,0\n10,5.2,1.2,0\n", encoding="utf-8")
    columns, problems = measure_all(MissionRun(TINY, trajectory, csv, "cross", "social", "elastic_band"))
    assert columns["duration_s"] == 10.0 and columns["clash_own"] == 2.0     # chronav's value kept
    assert any("metric 'raising_metric' failed on mission cross: ValueError: no such column" in p for p in problems)
    assert any("metric 'zz_clash': column(s) duration_s already given" in p for p in problems)

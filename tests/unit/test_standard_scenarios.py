"""The field's standard crowd scenarios shipped in scenes/crowds/: reproducible from their
generator, each passing the scene check, each run in-process to its end (the path a user takes)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from tests.support import REPO_ROOT
from tools import standard_scenarios
from tools.cli import app

runner = CliRunner()
SHIPPED = REPO_ROOT / "scenes" / "crowds"
NAMES = sorted(standard_scenarios.SCENARIOS)


def test_the_shipped_scenarios_are_their_generators_output(tmp_path: Path) -> None:
    """Each scene and its walks file are what tools/standard_scenarios.py writes from seed 0, and
    each scene says where its definition comes from."""
    standard_scenarios.write_all(tmp_path, seed=0)
    for name in NAMES:
        for suffix in (".yaml", ".txt"):
            assert (tmp_path / f"{name}{suffix}").read_text(encoding="utf-8") == \
                (SHIPPED / f"{name}{suffix}").read_text(encoding="utf-8"), f"regenerate {name}{suffix}"
        assert "# Where the definition comes from: " in (SHIPPED / f"{name}.yaml").read_text(encoding="utf-8")
    other = tmp_path / "seed1"
    standard_scenarios.write_all(other, seed=1)
    assert (other / "circle_crossing.txt").read_text() != (tmp_path / "circle_crossing.txt").read_text()


def test_the_standard_scenarios_pass_the_scene_check() -> None:
    result = runner.invoke(app, ["scene", "check", *[str(SHIPPED / f"{n}.yaml") for n in NAMES]])
    assert result.exit_code == 0, result.output
    assert result.output.count(": ok") == len(NAMES)


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
def test_each_standard_scenario_runs_in_process(tmp_path: Path, name: str) -> None:
    """By name, as a user types it; the robot's crossing completes among the reactive people."""
    launched = runner.invoke(app, ["launch", f"crowds/{name}", "--in-process", "--no-record", "--timeout", "150"],
                             env={"CHRONAV_RUNS": str(tmp_path)})
    assert launched.exit_code == 0, launched.output
    result = json.loads(next(tmp_path.glob("*/result.json")).read_text(encoding="utf-8"))
    assert result["missions"]["cross"]["state"] == "done"
    people = next(tmp_path.glob("*/people.csv")).read_text(encoding="utf-8").splitlines()
    assert len(people) > 10, "the robot drove among the people"


@pytest.mark.parametrize(("scene", "data", "replay"), [("ucy_uni_examples", "uni_examples.txt", ""),
                                                       ("ucy_zara03", "crowds_zara03.txt", ""),
                                                       ("ucy_uni_examples_reactive", "uni_examples.txt", "reactive"),
                                                       ("ucy_zara03_reactive", "crowds_zara03.txt", "reactive")])
def test_the_shipped_ucy_scenes_are_from_crowds_output(tmp_path: Path, scene: str, data: str, replay: str) -> None:
    """scenes/crowds/ucy_*.yaml are `chronav scene from-crowd scenes/data/pedestrians/FILE --out
    scenes/crowds/ucy_*.yaml --missions 3 --seed 0 [--replay reactive]` (their first comment line
    says so), and pass the check."""
    shipped = (SHIPPED / f"{scene}.yaml").read_text(encoding="utf-8")
    extra = ["--replay", replay] if replay else []
    assert shipped.startswith(f"# Written by `chronav scene from-crowd scenes/data/pedestrians/{data} --out "
                              f"scenes/crowds/{scene}.yaml --missions 3 --seed 0{' '.join(['', *extra])}`")
    out = tmp_path / "crowds" / f"{scene}.yaml"
    out.parent.mkdir()
    result = runner.invoke(app, ["scene", "from-crowd", str(REPO_ROOT / "scenes" / "data" / "pedestrians" / data),
                                 "--out", str(out), "--missions", "3", "--seed", "0", *extra])
    assert result.exit_code == 0, result.output
    body = out.read_text(encoding="utf-8")
    # the same scene; only the recording's reference differs (absolute from a temporary directory)
    assert body[body.index("\nname:"):] == shipped[shipped.index("\nname:"):].replace(
        "file: ../data/pedestrians/", f"file: {(REPO_ROOT / 'scenes' / 'data' / 'pedestrians').resolve()}/")
    assert runner.invoke(app, ["scene", "check", str(SHIPPED / f"{scene}.yaml")]).exit_code == 0

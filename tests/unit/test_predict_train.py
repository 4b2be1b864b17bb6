"""``chronav predict train``: the walker model trained on a site's own files, seeded and
reproducible, its provenance in the file; ``--model`` reaching the observer from launch and
evaluate, and predict evaluate using it."""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

from typer.testing import CliRunner

from dsr import DSRGraph
from tests.support import REPO_ROOT
from tools.cli import app

runner = CliRunner()


def _walkers(path: Path, frames: int = 40) -> Path:
    """Four people walking gentle curves (frames 10 apart, 0.4 s): enough windows to learn from."""
    lines = []
    for k in range(frames):
        t = 0.4 * k
        for pid, (cx, cy, r, w) in enumerate([(0, 0, 6.0, 0.18), (20, 0, 5.0, -0.2), (0, 20, 7.0, 0.15),
                                              (20, 20, 6.0, -0.17)], start=1):
            lines.append(f"{10 * k}\t{pid}\t{cx + r * math.cos(w * t):.5f}\t{cy + r * math.sin(w * t):.5f}")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _train(data: Path, out: Path, *extra: str) -> dict:
    result = runner.invoke(app, ["predict", "train", str(data), "--out", str(out), "--iterations", "15",
                                 "--noise-seeds", "1", "--json", *extra])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def test_predict_train_is_seeded_reproducible_and_names_its_data(tmp_path: Path) -> None:
    data = _walkers(tmp_path / "site.txt")
    a, b, c = tmp_path / "a.json", tmp_path / "b.json", tmp_path / "c.json"
    summary = _train(data, a, "--seed", "3")
    first = a.read_bytes()
    _train(data, a, "--seed", "3", "--force")
    assert a.read_bytes() == first, "the same command gives the same file"
    _train(data, b, "--seed", "3")
    _train(data, c, "--seed", "4")
    assert json.loads(a.read_text())["w1"] == json.loads(b.read_text())["w1"]
    assert json.loads(a.read_text())["w1"] != json.loads(c.read_text())["w1"], "another seed, another start"
    provenance = json.loads(a.read_text())["provenance"]
    assert provenance["files"][0]["name"] == "site.txt"
    assert provenance["files"][0]["sha256"] == hashlib.sha256(data.read_bytes()).hexdigest()
    assert provenance["seed"] == 3 and provenance["noise_m"] == 0.02 and provenance["noise_seeds"] == [1]
    assert provenance["command"].startswith("chronav predict train") and summary["examples"] > 0
    shipped = runner.invoke(app, ["predict", "evaluate", str(data), "--json"])
    mine = runner.invoke(app, ["predict", "evaluate", str(data), "--json", "--model", str(a)])
    assert json.loads(mine.stdout)["files"]["site.txt"]["ade"] != json.loads(shipped.stdout)["files"]["site.txt"]["ade"]
    again = runner.invoke(app, ["predict", "train", str(data), "--out", str(a)])
    assert again.exit_code == 2 and "exists; pass --force" in again.stderr


def test_predict_train_on_a_runs_people_csv(tmp_path: Path) -> None:
    rows = ["t,name,role,x,y,theta,vx,vy,group"]
    for k in range(200):
        t = 32400 + 0.1 * k
        rows.append(f"{t:.3f},ann,visitor,{0.9 * 0.1 * k:.4f},{0.3 * math.sin(0.05 * k):.4f},0,0.9,0,")
        rows.append(f"{t:.3f},bob,visitor,{10 - 0.8 * 0.1 * k:.4f},3.0000,3.14159,-0.8,0,")
    data = tmp_path / "people.csv"
    data.write_text("\n".join(rows) + "\n", encoding="utf-8")
    assert _train(data, tmp_path / "m.json")["files"][0]["name"] == "people.csv"


def test_bad_training_input_is_a_clear_error(tmp_path: Path) -> None:
    short = tmp_path / "short.txt"
    short.write_text("0 1 2.0 3.0\n10 1 2.1 3.0\n", encoding="utf-8")
    result = runner.invoke(app, ["predict", "train", str(short), "--out", str(tmp_path / "m.json")])
    assert result.exit_code == 2 and "short.txt: no window to train on" in result.stderr
    bad = tmp_path / "bad.txt"
    bad.write_text("0 1 2.0 x\n", encoding="utf-8")
    result = runner.invoke(app, ["predict", "train", str(bad), "--out", str(tmp_path / "m.json")])
    assert result.exit_code == 2 and "bad.txt:1:" in result.stderr and "Traceback" not in result.output


def test_model_reaches_the_observer_through_its_config(tmp_path: Path) -> None:
    """launch/evaluate --model become the observer's ``walker_model`` option, which its tracker loads."""
    from agents.lib.perception.walker_model import load
    from agents.runtime.recording import Recorder
    from tools.evaluate.sweep import agent_options, plan_sweep
    from tools.inprocess import build_agents
    from tools.walker_models import model_options

    model = tmp_path / "m.json"
    _train(_walkers(tmp_path / "site.txt"), model)
    options = model_options(model)
    assert options == {"human_observer": [f"walker_model={model.resolve()}"]}
    spec = plan_sweep([REPO_ROOT / "scenes" / "crowds" / "circle_crossing.yaml"], ["social"], [1],
                      model=str(model.resolve()))[0]
    assert f"walker_model={model.resolve()}" in agent_options(spec)["human_observer"]
    assert spec.key.endswith(str(model.resolve())), "a study with another model is another run"
    scene = REPO_ROOT / "scenes" / "crowds" / "circle_crossing.yaml"
    observer = build_agents(scene, ["human_observer"],
                            options={"human_observer": dict(o.split("=", 1) for o in options["human_observer"])})[0]
    observer.setup(DSRGraph(agent="test_observer"), Recorder("human_observer", None, None))
    assert observer.tracker.model is not None
    assert observer.tracker.model.provenance == load(model).provenance


def test_a_bad_model_is_refused_before_anything_runs(tmp_path: Path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text("{}", encoding="utf-8")
    for command in (["launch", "crowds/circle_crossing", "--in-process", "--model", str(bad)],
                    ["evaluate", "crowds/circle_crossing", "--seeds", "1", "--model", str(bad),
                     "--out", str(tmp_path / "study")]):
        result = runner.invoke(app, command, env={"COLUMNS": "1000"})   # the error box: the path on one line
        assert result.exit_code == 2, result.output
        assert "bad.json" in result.output and "Traceback" not in result.output


def test_training_also_learns_each_walk_scaled(tmp_path: Path) -> None:
    """Speed augmentation (train_prediction.SCALES): a scaled copy is the same walks that much
    faster, seen through fresh detection noise of the same size; the file's provenance says so."""
    import numpy as np

    from tools import train_prediction

    data = _walkers(tmp_path / "site.txt")
    plain = train_prediction.examples(data, 0.02, 1)
    fast = train_prediction.examples(data, 0.02, 1, scale=1.25)
    assert len(fast[0]) == len(plain[0]) > 0
    assert abs(float(np.median(fast[1] / plain[1])) - 1.25) < 0.03        # fit speeds, within the noise
    assert not np.allclose(fast[1], 1.25 * plain[1], atol=1e-6)             # fresh noise, not the same draw scaled
    summary = _train(data, tmp_path / "m.json")
    assert summary["scales"] == list(train_prediction.SCALES) and summary["mirrored"] is True
    assert summary["training_examples"] == 2 * len(train_prediction.SCALES) * summary["examples"]

"""`chronav export RUN --format mcap`: a run's files as a rosbag2 MCAP file that rosbags' AnyReader
and the mcap library (with mcap-ros2-support) both read, every message decoding, stamped in the
scene's clock.  The run directory is written here as the simulator writes one (trajectory.csv,
people.csv, result.json); tests/system/test_ros_bridge.py exports a real run too."""

from __future__ import annotations

import datetime as dt
import json
import subprocess
import sys
from pathlib import Path
from zoneinfo import ZoneInfo

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from tests.integration.ros2_client import read_back
from tests.support import REPO_ROOT

from agents.world.plans_file import PlansWriter

SCENE = REPO_ROOT / "tests" / "data" / "ros_lounge.yaml"
T0 = 36_000.0   # 10:00:00


def _run_dir(tmp_path: Path) -> Path:
    run = tmp_path / "ros_lounge-run"
    run.mkdir()
    (run / "result.json").write_text(json.dumps({"scene": "ros_lounge", "scene_path": str(SCENE)}))
    rows = ["t,x,y,theta"] + [f"{T0 + 0.1 * i:.3f},{0.8 + 0.05 * i:.4f},1.2000,0.00000" for i in range(20)]
    rows += [f"{T0 + 100 + 0.1 * i:.3f},{1.8 + 0.05 * i:.4f},1.2000,0.00000" for i in range(10)]   # a second drive
    (run / "trajectory.csv").write_text("\n".join(rows) + "\n")
    people = ["t,name,role,x,y,theta,vx,vy,group"]
    for i in range(20):
        people += [f"{T0 + 0.1 * i:.3f},ana,resident,3.6000,1.5000,-1.57080,0.0000,0.0000,",
                   f"{T0 + 0.1 * i:.3f},ben,resident,{1.5 + 0.02 * i:.4f},3.2000,0.00000,0.2000,0.0000,"]
    (run / "people.csv").write_text("\n".join(people) + "\n")
    plans = PlansWriter(run)   # as the navigation agent writes it
    plans.adopted(T0, [0.8, 1.5, 1.8], [1.2, 1.2, 1.5], 12.5, "new goal")
    plans.adopted(T0 + 100, [1.8, 2.4], [1.2, 1.2], 4.0, "replan")
    plans.close()
    return run


def _export(run: Path, out: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "tools.cli", "export", str(run), "--format", "mcap", "--out",
                           str(out), "--json"], capture_output=True, text=True, timeout=120, cwd=REPO_ROOT,
                          check=False)


def test_export_writes_a_bag_both_readers_decode(tmp_path: Path) -> None:
    run = _run_dir(tmp_path)
    out = tmp_path / "run.mcap"
    done = _export(run, out)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    topics = read_back(out)
    assert summary["messages"] == {k: len(v) for k, v in topics.items()}
    assert len(topics["/odom"]) == 30 and len(topics["/people"]) == 20 and len(topics["/map"]) == 1
    assert len(topics["/social_costmap"]) == 2 == len(topics["/agenda"])   # one per drive
    midnight = dt.datetime(2026, 11, 25, tzinfo=ZoneInfo("Europe/Madrid")).timestamp()
    first_ns, first = topics["/odom"][0]
    assert first_ns == round((midnight + T0) * 1e9) and first.header.stamp.sec == int(midnight + T0)
    assert first.pose.pose.position.x == pytest.approx(0.8) and first.child_frame_id == "base_link"
    assert topics["/odom"][5][1].twist.twist.linear.x == pytest.approx(0.5)
    ben = next(p for p in topics["/people"][10][1].people if p.name == "ben")
    assert (ben.position.x, ben.velocity.x) == (pytest.approx(1.7), pytest.approx(0.2))
    grid = topics["/map"][0][1]
    assert (grid.info.width, grid.info.height, grid.info.resolution) == (120, 80, pytest.approx(0.05))
    agenda = json.loads(topics["/agenda"][0][1].data)
    assert agenda["activities"][0]["id"] == "game" and agenda["activities"][0]["state"] == "running"
    stamps = [ns for v in topics.values() for ns, _ in v]
    assert min(stamps) == first_ns
    # the adopted plans, as rosbags reads them and as mcap-ros2-support decodes them
    plans = topics["/plan"]
    assert [ns for ns, _ in plans] == [first_ns, round((midnight + T0 + 100) * 1e9)]
    assert [(p.pose.position.x, p.pose.position.y) for p in plans[0][1].poses] == [(0.8, 1.2), (1.5, 1.2), (1.8, 1.5)]
    assert plans[1][1].header.frame_id == "map" and plans[1][1].header.stamp.sec == int(midnight + T0 + 100)
    with out.open("rb") as handle:
        decoded = [(message.log_time, ros) for _schema, channel, message, ros in
                   make_reader(handle, decoder_factories=[DecoderFactory()]).iter_decoded_messages()
                   if channel.topic == "/plan"]
    assert [ns for ns, _ in decoded] == [ns for ns, _ in plans]
    assert [(p.pose.position.x, p.pose.position.y) for p in decoded[1][1].poses] == [(1.8, 1.2), (2.4, 1.2)]


def test_a_bad_run_is_refused_with_the_file_and_line(tmp_path: Path) -> None:
    run = _run_dir(tmp_path)
    text = (run / "trajectory.csv").read_text().splitlines()
    text[3] = "36000.300,zero,1.2,0"
    (run / "trajectory.csv").write_text("\n".join(text) + "\n")
    done = _export(run, tmp_path / "bad.mcap")
    assert done.returncode == 1 and "trajectory.csv:4" in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "bad.mcap").exists()
    (run / "result.json").unlink()
    done = _export(run, tmp_path / "bad.mcap")
    assert done.returncode == 1 and "no result.json" in done.stderr


def test_a_bad_plans_file_is_refused_with_the_file_line_and_key(tmp_path: Path) -> None:
    run = _run_dir(tmp_path)
    with (run / "plans.jsonl").open("a") as handle:
        handle.write('{"t_s": 36200.0, "x": [1e308], "y": [1.0]}\n')
    done = _export(run, tmp_path / "bad.mcap")
    assert done.returncode == 1 and "plans.jsonl:3" in done.stderr and "x" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and not (tmp_path / "bad.mcap").exists()

"""Fuzzing trajectory CSV files (`chronav metrics`, the demo report): any file gives an (N, 4)
array of finite samples in time order, or a TrajectoryFormatError naming the file; never
another exception (csv, numpy and float() all raise their own kinds on odd input)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from agents.lib.metrics.metrics import TrajectoryFormatError, read_trajectory_csv
from tests.unit.fuzz_mutations import fuzz_settings, mutated_bytes, token_soup

# What the simulator writes (agents/sim_robot/agent.py), with a restart's blank line and a pause.
VALID = "t,x,y,theta\n" + "".join(f"{34200 + 0.1 * i:.3f},{12 - 0.05 * i:.4f},{2 + 0.01 * i:.4f},{3.14159:.5f}\n"
                                   for i in range(12)) + "\n34201.300,11.4000,2.1200,3.14159\n"


def check_file(path: Path) -> None:
    try:
        samples = read_trajectory_csv(path)
    except TrajectoryFormatError as exc:
        assert str(exc).startswith(str(path)), f"the error does not start with the file name: {exc}"
        return
    assert samples.ndim == 2 and samples.shape[1] == 4 and len(samples) >= 1
    assert np.all(np.isfinite(samples)) and np.all(np.diff(samples[:, 0]) >= 0)


def test_valid_file_reads(tmp_path: Path) -> None:
    path = tmp_path / "trajectory.csv"
    path.write_text(VALID)
    assert read_trajectory_csv(path).shape == (13, 4)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz_trajectory")


@fuzz_settings(200)
@given(content=st.one_of(mutated_bytes(VALID), st.binary(max_size=64),
                         token_soup(VALID, (",", "\r\n", '"', "nan", "-inf", "1e999")).map(str.encode)))
def test_mutated_trajectory_files_give_format_errors(workdir: Path, content: bytes) -> None:
    path = workdir / "trajectory.csv"
    path.write_bytes(content)
    check_file(path)

"""Fuzzing scene files: whatever a scene file holds, load_scene answers with a SourceError that
names the file, line and column, or with a scene; never with another exception.

Mutations start from every shipped scene (and the test scenes), so they reach the schema, the
geometry checks and the scene's agenda, not only the YAML parser."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from agents.world.scene_world import load_world as load_scene  # the full check: schema, geometry, agenda
from scenes.loader import SCENES_DIR
from scenes.yamlio import SourceError
from tests.support import REPO_ROOT
from tests.unit.fuzz_mutations import fuzz_settings, mutated_bytes, token_soup

SOURCES: list[Path] = sorted([*SCENES_DIR.glob("*.yaml"), *(REPO_ROOT / "tests" / "data").glob("*.yaml")])
SCENE_WORDS = ("name", "clock", "walls", "rooms", "doors", "objects", "people", "robot", "agenda", "missions",
               "pose", "polygon", "footprint", "interaction", "shape", "waypoints", "time", "goal", "agenda_file")


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """A directory with the scenes' companion files, so relative agenda_file references resolve."""
    path = tmp_path_factory.mktemp("fuzz_scenes")
    for companion in SCENES_DIR.iterdir():
        if companion.suffix in (".ics", ".yml") or companion.name.startswith("agenda"):
            shutil.copy(companion, path / companion.name)
    shutil.copytree(SCENES_DIR / "maps", path / "maps")   # building maps (map_ward)
    yield path


def check_scene_file(path: Path) -> None:
    """Load; the only acceptable failure is a located SourceError."""
    try:
        load_scene(path)
    except SourceError as exc:
        assert (exc.line is None or exc.line >= 1) and (exc.column is None or exc.column >= 1), exc
        assert exc.message.strip(), exc
        assert Path(exc.file).name == path.name or Path(exc.file).resolve().is_relative_to(path.parent.resolve()), \
            f"error names {exc.file!r}, not the scene or a file it references (agenda, map): {exc}"


def test_shipped_scenes_load() -> None:
    for source in SOURCES:
        load_scene(source)


@fuzz_settings(250)
@given(data=st.data())
def test_mutated_scene_files_give_located_errors(workdir: Path, data: st.DataObject) -> None:
    source = data.draw(st.sampled_from(SOURCES), label="source")
    path = workdir / source.name
    path.write_bytes(data.draw(mutated_bytes(source.read_text(encoding="utf-8")), label="content"))
    check_scene_file(path)


@fuzz_settings(100)
@given(text=st.one_of(st.text(max_size=200), token_soup((SCENES_DIR / "icra_usecase.yaml").read_text(), SCENE_WORDS)))
def test_random_text_scene_files_give_located_errors(workdir: Path, text: str) -> None:
    path = workdir / "random.yaml"
    path.write_text(text, encoding="utf-8")
    check_scene_file(path)


def test_crashes_found_by_fuzzing_are_located_errors(workdir: Path) -> None:
    icra = (SCENES_DIR / "icra_usecase.yaml").read_text(encoding="utf-8")
    path = workdir / "latin1.yaml"  # was UnicodeDecodeError
    path.write_bytes(icra.replace("description: Occ", "description: Terap\xeda Occ").encode("latin-1"))
    with pytest.raises(SourceError, match="not UTF-8") as info:
        load_scene(path)
    assert (info.value.line, info.value.column) == (8, 19)
    path = workdir / "bowtie.yaml"  # a self-intersecting room was a GEOSException in the union of rooms
    path.write_text(icra.replace("[[9, 0], [14, 0], [14, 7], [9, 7]]", "[[9, 0], [14, 7], [14, 0], [9, 7]]"))
    with pytest.raises(SourceError, match="self-intersects") as info:
        load_scene(path)
    assert info.value.key == "rooms[1].polygon"

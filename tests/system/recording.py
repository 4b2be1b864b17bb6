"""Read a merged chronav recording back with Rerun's own API (rerun.chunk), for system tests."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


def load_store(path: Path) -> Any:
    from rerun.chunk import RrdReader

    reader = RrdReader(str(path))
    assert len(reader.recordings()) == 1, f"{path} holds {len(reader.recordings())} recordings, expected 1"
    return reader.stream().collect()


def strips_over_time(store: Any, entity: str) -> list[tuple[float, np.ndarray]]:
    """(sim time in s, first strip as an (n, 2) array) for every logged LineStrips2D of ``entity``."""
    table = store.reader(index="sim_time", contents=entity).to_arrow_table()
    column = table.column(f"{entity}:LineStrips2D:strips")
    out = []
    for when, strips in zip(table.column("sim_time").to_pylist(), column.to_pylist(), strict=True):
        if strips:
            out.append((when.total_seconds(), np.asarray(strips[0], dtype=float)))
    return out


def texts(store: Any, entity: str) -> list[tuple[float, str]]:
    table = store.reader(index="sim_time", contents=entity).to_arrow_table()
    column = table.column(f"{entity}:TextLog:text")
    return [(when.total_seconds(), text[0]) for when, text in zip(table.column("sim_time").to_pylist(),
                                                                  column.to_pylist(), strict=True) if text]

"""read_bounded asks for memory by what the file holds, never by its bound (issue 42, point 6).

The hostile-input round found people.csv read under a 4 GB address-space limit ending in
MemoryError: ``read_bounded`` asked for ``max_bytes + 1`` bytes in one read, even for a file of a
few kilobytes.  The regression test reads a small file with a bound far above the limit, in a
subprocess whose address space is capped (``resource.setrlimit(RLIMIT_AS)``)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from scenes.reading import FileTooLarge, _read_upto, read_bounded

resource = pytest.importorskip("resource")

LIMIT_BYTES = 2 * 1024**3          # the subprocess's address space
BOUND_BYTES = 8 * 1024**3          # the caller's bound: 4 x the whole address space


def test_a_small_file_is_read_under_an_address_space_limit(tmp_path: Path) -> None:
    target = tmp_path / "people.csv"
    target.write_text("t,name,x,y,theta,vx,vy\n" + "1.0,ana,1.0,2.0,0.0,0.0,0.0\n" * 100, encoding="utf-8")
    script = textwrap.dedent(f"""
        import resource, sys
        from scenes.reading import read_bounded
        resource.setrlimit(resource.RLIMIT_AS, ({LIMIT_BYTES}, {LIMIT_BYTES}))
        try:
            bytearray({BOUND_BYTES})   # the old single read's reservation: must fail here
        except MemoryError:
            pass
        else:
            sys.exit("the address-space limit does not hold: the test proves nothing")
        data = read_bounded(sys.argv[1], max_bytes={BOUND_BYTES}, what="people file")
        print(len(data))
    """)
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-c", script, str(target)], capture_output=True, text=True, env=env,
                          timeout=60, cwd=Path(__file__).resolve().parents[2])
    assert done.returncode == 0, done.stderr
    assert int(done.stdout) == target.stat().st_size


def test_the_bound_is_still_kept(tmp_path: Path) -> None:
    target = tmp_path / "big.csv"
    target.write_bytes(b"x" * 1000)
    with pytest.raises(FileTooLarge):
        read_bounded(target, max_bytes=999)
    assert read_bounded(target, max_bytes=1000) == b"x" * 1000


def test_a_file_longer_than_its_size_said_is_read_in_chunks_up_to_the_bound() -> None:
    """A pipe's fstat size is 0: what it holds beyond that comes in chunks, and reading stops one
    byte past the bound (the caller then refuses it as grown)."""
    read_end, write_end = os.pipe()
    try:
        os.write(write_end, b"y" * 50_000)
        os.close(write_end)
        write_end = -1
        assert _read_upto(read_end, 0, 100_000) == b"y" * 50_000
    finally:
        os.close(read_end)
        if write_end >= 0:
            os.close(write_end)
    read_end, write_end = os.pipe()
    try:
        os.write(write_end, b"z" * 50_000)
        assert len(_read_upto(read_end, 0, 30_000)) == 30_001
    finally:
        os.close(read_end)
        os.close(write_end)

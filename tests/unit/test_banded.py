"""The compiled banding of a predicted position (agents/lib/socialmap/banded.py) gives the costs the
numpy code gave: the weighted asymmetric Gaussian against the zone levels, cell for cell."""

from __future__ import annotations

import math

import numpy as np

from agents.lib.socialmap.banded import banded_gaussian
from agents.lib.socialmap.grid import COST_DTYPE
from agents.lib.socialmap.personal_space import PersonalSpace, asymmetric_gaussian


def _numpy_bands(space: PersonalSpace, x0: float, y0: float, theta: float, xs: np.ndarray, ys: np.ndarray,
                 w: float, levels: np.ndarray, table: np.ndarray) -> np.ndarray:
    density = w * asymmetric_gaussian(space, x0, y0, theta, xs[np.newaxis, :], ys[:, np.newaxis])
    index = (density >= levels[0]).astype(np.int8) + (density >= levels[1]) + (density >= levels[2])
    return table[index]


def test_banded_gaussian_equals_the_numpy_banding_cell_for_cell() -> None:
    rng = np.random.default_rng(7)
    table = np.array([0.0, 3.0, 10.0, math.inf], dtype=COST_DTYPE)
    levels = np.array([0.1, 0.4, 0.8])
    bands_seen: set[float] = set()
    for _ in range(300):
        space = PersonalSpace(*rng.uniform(0.2, 3.0, 4))
        x0, y0 = rng.uniform(-3, 3), rng.uniform(-3, 3)
        theta = float(rng.choice([rng.uniform(-4, 4), 0.0, math.pi / 2, math.pi, -math.pi / 2]))  # axis-aligned too
        xs = -4 + (np.arange(rng.integers(1, 120)) + 0.5) * 0.05
        ys = -4 + (np.arange(rng.integers(1, 120)) + 0.5) * 0.05
        w = float(rng.choice([rng.uniform(0.05, 1.0), 1.0, 0.1]))
        ours = banded_gaussian(space, x0, y0, theta, xs, ys, w, levels, table)
        theirs = _numpy_bands(space, x0, y0, theta, xs, ys, w, levels, table)
        assert ours.dtype == theirs.dtype and ours.shape == theirs.shape
        np.testing.assert_array_equal(ours, theirs)
        bands_seen |= set(np.unique(ours).tolist())
    assert bands_seen == {0.0, 3.0, 10.0, math.inf}, "every band is exercised"


def test_zone_patches_equal_the_banded_densities_cell_for_cell() -> None:
    """zones.zone_patches (the compiled group banding the map builds) against the definition it
    replaces: band_patches of density_windows, for lone people and groups of up to five."""
    from agents.lib.socialmap.groups import Group
    from agents.lib.socialmap.grid import GridSpec
    from agents.lib.socialmap.types import Person
    from agents.lib.socialmap.zones import ZoneParams, band_patches, density_windows, zone_patches

    rng = np.random.default_rng(11)
    spec = GridSpec(x0=-6.0, y0=-5.0, resolution=0.05, rows=200, cols=240)
    params = ZoneParams()
    bands_seen: set[float] = set()
    for _ in range(120):
        n = int(rng.integers(1, 6))
        people = [Person(f"p{i}", float(rng.uniform(-7, 7)), float(rng.uniform(-6, 6)),
                         float(rng.choice([rng.uniform(-4, 4), 0.0, math.pi / 2, -math.pi])))    # axis-aligned too
                  for i in range(n)]
        spaces = [PersonalSpace(*rng.uniform(0.2, 2.0, 4)) for _ in range(n)]
        cut = int(rng.integers(1, n + 1))       # a group and the rest alone
        groups = [Group(members=tuple(range(cut)), names=tuple(p.name for p in people[:cut]), k=0, delta=0.0, phi=1.0),
                  *(Group(members=(i,), names=(people[i].name,), k=0, delta=0.0, phi=1.0) for i in range(cut, n))]
        ours = zone_patches(spec, people, spaces, groups, params, 3.0, 10.0)
        theirs = band_patches(density_windows(spec, people, spaces, groups, params), params, 3.0, 10.0)
        assert len(ours) == len(theirs)
        for a, b in zip(ours, theirs, strict=True):
            assert (a.rows, a.cols) == (b.rows, b.cols) and a.values.dtype == b.values.dtype
            np.testing.assert_array_equal(a.values, b.values)
            bands_seen |= set(np.unique(a.values).tolist())
    assert bands_seen == {0.0, 3.0, 10.0, math.inf}, "every band is exercised"


def test_banded_gaussians_are_banded_gaussian_at_each_centre() -> None:
    """The batch a walker's predicted positions are banded with gives each position's banded_gaussian."""
    from agents.lib.socialmap.banded import banded_gaussians

    rng = np.random.default_rng(5)
    table = np.array([0.0, 3.0, 10.0, math.inf], dtype=COST_DTYPE)
    levels = np.array([0.1, 0.4, 0.8])
    space, theta = PersonalSpace(1.0, 0.5, 0.67, 0.67), 0.9
    centres = [(float(rng.uniform(-2, 2)), float(rng.uniform(-2, 2)), float(rng.uniform(0.1, 1.0)),
                -4 + (np.arange(rng.integers(1, 90)) + 0.5) * 0.05, -4 + (np.arange(rng.integers(1, 90)) + 0.5) * 0.05)
               for _ in range(40)]
    for (x, y, w, xs, ys), ours in zip(centres, banded_gaussians(space, theta, centres, levels, table), strict=True):
        np.testing.assert_array_equal(ours, banded_gaussian(space, x, y, theta, xs, ys, w, levels, table))
    assert banded_gaussians(space, theta, [], levels, table) == []


_FIRST_MAP_AFTER_WARM_UP = """
import json
import numpy as np
from agents.lib.socialmap import banded
from agents.lib.socialmap.grid import COST_DTYPE, GridSpec
from agents.lib.socialmap.personal_space import PersonalSpace

banded.warm_up()
kernels = (banded._banded, banded._banded_sum)
before = [len(k.signatures) for k in kernels]
spec = GridSpec(0.0, 0.0, 0.1, 40, 40)
space, levels = PersonalSpace(1.0, 0.5, 0.7, 0.7), np.array([0.1, 0.4, 0.8])
table = np.array([0.0, 1.0, 2.0, np.inf], dtype=COST_DTYPE)
banded.banded_gaussian(space, 2.0, 2.0, 0.3, spec.xs(slice(5, 30)), spec.ys(slice(5, 30)), 0.5, levels, table)
banded.banded_group([space, space], [(1.5, 2.0, 0.0), (2.5, 2.0, 3.1)], spec.xs(), spec.ys(), levels, table)
print(json.dumps([before, [len(k.signatures) for k in kernels]]))
"""


def test_the_warm_up_compiles_the_signatures_a_map_uses() -> None:
    """A social map's people, banded after the agent's warm-up, compile nothing more: numba
    compiles a read-only array (the map's cell centres, GridSpec.xs) as a signature of its own, and
    the warm-up once passed writable ones, so the first map with people compiled both kernels again
    mid-mission.  In a fresh process: this one's other tests may have compiled either already."""
    import json
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", _FIRST_MAP_AFTER_WARM_UP], capture_output=True, text=True,
                          timeout=120, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    before, after = json.loads(done.stdout.strip().splitlines()[-1])   # signatures per kernel
    assert after == before, done.stdout

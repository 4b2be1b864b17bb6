"""The time-dependent social map: one entry point for the agent, the tools and the tests.

    static = build_static_map(bounds, walls, rooms, params)          # once per building
    smap = build_social_map(bounds, walls, people, objects, activities, t_s, params, static=static)

Planning on it is agents.lib.planning (``plan(smap, start_xy, goal_xy, planner="social")``); the
map holds no planner parameters, so one map serves every planner of a study.

Layers (Nav2 style, composed by cell-wise maximum, grid.py):
  static  walls inflated by the robot radius, outside the rooms          -> ``static``
  + bodies (person radius + robot radius) and object footprints           -> ``physical`` (baseline)
  + people's zones: social 2, personal 4, intimate forbidden              -> ``people_cost``
  + interaction spaces at R(t_s) (or forbidden while active)              -> ``cost`` (departure-time)
The ``social`` planner replaces the last layer by R at each cell's arrival time.

Default parameters and where they come from ("seed" = time-dependent-social-navigation-framework,
"affordance" = time-dependent-affordance-spaces, "adaptive" = adaptive-personal-space):

=============================================  ==========  ==============================================
parameter                                      default     source
=============================================  ==========  ==============================================
personal_space.sigma_h / sigma_r / sigma_s     2, 1, 4/3   seed 4.1 (after Eq. 4); affordance IV-B
personal_space.sigma_unit_m                    0.5 m       ours: fits seed Tables 1-2 (personal_space.py);
                                                           so 1.0 m ahead, 0.5 m behind, 0.67 m sides
zones.intimate / personal / social levels      0.8/0.4/0.1 RoboComp code of the seeds' experiments (zones.py)
grid.free_cost / social_cost / personal_cost   1 / 2 / 4   seed 5.1, 5.2.1; affordance V-B
intimate zone                                  forbidden   seed 5.2.1; affordance V-B
grid.resolution_m                              0.05 m      issue 3 (the seeds do not state one)
grid.robot_radius_m                            0.3 m       scene schema default (scenes/model.py)
grid.person_radius_m                           0.25 m      ours; body + robot = 0.55 m, near the seed
                                                           baseline's 0.51 m closest approach (Table 1)
grid.inflate_footprints                        True        ours (footprints are obstacles, seed 5.2.2)
groups.omega_d_m / omega_theta_rad             2 m, pi/2   ours; seed 4.1 defers to its ref. 37
groups.composition                             max         ours; "sum" is seed Eq. 5 literally (groups.py)
group threshold phi                            1 + k delta seed Eqs. 6-8
roles.scales                                   resident 1, new_resident 1.25, staff/therapist 0.75,
                                                           visitor 1: ours (seed section 7 future work)
adaptive.enabled                               True        adaptive seed
adaptive.margin_m / d_min_m / d_max_m          0.1/0.45/1.2 ours (adaptive seed gives no numbers)
adaptive.zone (contour moved to d_s)           personal    adaptive seed ("distance to the personal space")
adaptive.robot_diameter_m                      None        2 x grid.robot_radius_m; a scene's maps: the body's 2 x radius
                                                           (adaptive seed: d_r = robot diameter + margin; issue 43)
chronemics.r_min / r_max                       1.5 / 3.5   seed 5.2.2, Fig. 8; affordance V-B, Fig. 6
chronemics.ramp_before_s / ramp_after_s        2700 s      seed 5.2.2 (45 minutes, same after the end)
chronemics.band_edges                          1.5 2 2.5 3 3.5  affordance V-B (four colour intervals)
forbidden_while_active (per object)            False       affordance IV-A ("cannot use this space")
=============================================  ==========  ==============================================
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np
import shapely
from pydantic import BaseModel, ConfigDict
from shapely.geometry.base import BaseGeometry

from agents.lib.socialmap.adaptive import Adaptation, AdaptiveParams, adapt_spaces
from agents.lib.socialmap.arrival import time_costs
from agents.lib.agenda.chronemics import (
    ChronemicsParams,
    interaction_cost_profiles,
    is_active,
    r_band,
    r_profiles,
)
from agents.lib.socialmap.grid import (
    CostArray,
    CostPatch,
    GridParams,
    GridSpec,
    TimeCosts,
    compose,
    static_grid,
    walls_geometry,
)
from agents.lib.socialmap.groups import Group, GroupParams, group_people, social_density
from agents.lib.socialmap.incremental import IncrementalTimeCosts
from agents.lib.socialmap.layers import (
    CellMask,
    body_patches,
    footprint_patches,
    interaction_masks,
    interaction_patches,
)
from agents.lib.socialmap.motion import MotionParams, Prediction, oriented, predict_many, prediction_patches, stretched
from agents.lib.socialmap.objects import ObjectGeometry, object_geometry
from agents.lib.socialmap.personal_space import PersonalSpace, PersonalSpaceParams
from agents.lib.socialmap.occupancy import OccupancyLayer
from agents.lib.socialmap.roles import RoleParams, role_scale
from agents.lib.agenda.model import ActivityWindow
from agents.lib.socialmap.types import Person, Room, SocialMapInputError, SocialObject, Wall
from agents.lib.socialmap.zones import (
    ZONE_NAMES,
    DensityWindow,
    GroupZones,
    ZoneParams,
    contour_zones,
    density_windows,
    zone_patches,
)


T = TypeVar("T")


class SocialMapParams(BaseModel):
    """Every tunable of the social map (defaults: table in the module doc; the planner's own are
    agents.lib.planning.plan.PlannerParams: a map does not carry a planner's parameters)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    grid: GridParams = GridParams()
    personal_space: PersonalSpaceParams = PersonalSpaceParams()
    roles: RoleParams = RoleParams()
    zones: ZoneParams = ZoneParams()
    groups: GroupParams = GroupParams()
    adaptive: AdaptiveParams = AdaptiveParams()
    chronemics: ChronemicsParams = ChronemicsParams()
    motion: MotionParams = MotionParams()


@dataclass(frozen=True, slots=True)
class StaticMap:
    """The building part of the map (walls, rooms, a building map's wall cells), reused across rebuilds."""

    spec: GridSpec
    grid: CostArray
    walls: BaseGeometry | None
    key: tuple[Any, ...]
    occupancy: OccupancyLayer | None = None


@dataclass(frozen=True, slots=True)
class ObjectSpace:
    """An object's polygons and the state of its interaction space at the map's time."""

    name: str
    kind: str
    footprint: BaseGeometry
    interaction: BaseGeometry
    r: float                  # R(t_s)
    band: int                 # colour band of r (chronemics.BAND_NAMES)
    active: bool              # an activity runs at t_s
    forbidden: bool           # active and forbidden_while_active: an obstacle now
    cost: float               # what the grid holds: r, or inf when forbidden


@dataclass(frozen=True, slots=True)
class PersonSpace:
    """A person's final personal space (role-scaled, then adapted) and what the adaptation did."""

    name: str
    space: PersonalSpace
    adaptation: Adaptation


@dataclass(frozen=True, slots=True)
class SocialMap:
    """Everything a planner, a visualiser or a metric needs about the social map at time ``t_s``."""

    spec: GridSpec
    params: SocialMapParams
    t_s: float
    people: tuple[Person, ...]
    objects: tuple[SocialObject, ...]
    activities: tuple[ActivityWindow, ...]
    unmatched_activities: tuple[ActivityWindow, ...]   # name an object not in the map: ignored
    person_spaces: tuple[PersonSpace, ...]
    groups: tuple[Group, ...]
    object_spaces: tuple[ObjectSpace, ...]
    static: CostArray          # walls and rooms (shared with the StaticMap, never written)
    obstacle_patches: tuple[CostPatch, ...]      # bodies and footprints
    zone_patches: tuple[CostPatch, ...]          # people's cost bands
    interaction_patches: tuple[CostPatch, ...]   # interaction spaces at R(t_s)
    interaction_cells: tuple[CellMask | None, ...]
    predictions: tuple[Prediction, ...] = ()
    prediction_patches: tuple[CostPatch, ...] = ()   # where walkers will be (motion.py): never intimate
    _cache: dict[Any, Any] = field(default_factory=dict, repr=False, compare=False)

    # The three grids are composed on first use: a rebuild followed by the default (arrival-time)
    # plan needs only ``people_cost``, and each full-grid copy costs milliseconds at 1000^2.
    @property
    def physical(self) -> CostArray:
        """Walls, rooms, bodies and footprints: the grid of the non-social baseline."""
        if "physical" not in self._cache:
            self._cache["physical"] = compose(self.static, self.obstacle_patches)
        return self._cache["physical"]

    @property
    def people_layers(self) -> tuple[CostPatch, ...]:
        """The patches of ``people_cost`` over the static grid: bodies, footprints, zones, predictions."""
        return (*self.obstacle_patches, *self.zone_patches, *self.prediction_patches)

    @property
    def people_cost(self) -> CostArray:
        """``physical`` plus the people's zones (the arrival-time planner's static part)."""
        if "people_cost" not in self._cache:
            self._cache["people_cost"] = compose(self.static, self.people_layers)
        return self._cache["people_cost"]

    @property
    def cost(self) -> CostArray:
        """``people_cost`` plus the interaction spaces at R(t_s): the departure-time social grid."""
        if "cost" not in self._cache:
            self._cache["cost"] = compose(self.static, (*self.people_layers, *self.interaction_patches))
        return self._cache["cost"]

    def cached(self, key: Hashable, build: Callable[[], T]) -> T:
        """The value derived from this map under ``key``, built by ``build()`` on first use.
        Why public: the planners (planners.py) derive further grids from a map and keep them with
        it, as the properties above do, without writing the map's private cache."""
        if key not in self._cache:
            self._cache[key] = build()
        return self._cache[key]

    @property
    def density(self) -> tuple[DensityWindow, ...]:
        """Each group's density on its window (zones.density_windows), computed on first use: the
        planners need only its bands (``zone_patches``, built without it), the zone polygons need it."""
        if "density" not in self._cache:
            spaces = [ps.space for ps in self.person_spaces]
            self._cache["density"] = tuple(density_windows(self.spec, self.people, spaces, self.groups,
                                                           self.params.zones))
        return self._cache["density"]

    def zones(self) -> list[GroupZones]:
        """Zone polygons per group (contoured on first use, then cached)."""
        if "zones" not in self._cache:
            self._cache["zones"] = contour_zones(self.spec, self.density, self.params.zones)
        return self._cache["zones"]

    def zone_polygons(self) -> dict[str, BaseGeometry]:
        """Union over groups of each zone (nested regions), e.g. for metrics.compute_metrics."""
        zones = self.zones()
        return {name: shapely.union_all([z.zone(name) for z in zones]) if zones else shapely.MultiPolygon()
                for name in ZONE_NAMES}

    def unadapted_zone_polygons(self) -> dict[str, BaseGeometry] | None:
        """The zones the people's spaces would have without the wall adaptation (the same people,
        roles, motion and groups rule), or None when the adaptation changed no one's space.

        Why: Psi is measured on the zones the planner used (``zone_polygons``); the unadapted
        figure beside it shows what the adaptation conceded near walls (docs/metrics.md)."""
        if not any(ps.adaptation.adapted for ps in self.person_spaces):
            return None
        if "unadapted_zones" not in self._cache:
            params = self.params
            spaces = [stretched(PersonalSpace.from_params(params.personal_space, role_scale(p, params.roles)), p,
                                role_scale(p, params.roles), params.motion) for p in self.people]
            groups = group_people(self.people, spaces, params.groups)
            windows = density_windows(self.spec, self.people, spaces, groups, params.zones)
            zones = contour_zones(self.spec, tuple(windows), params.zones)
            self._cache["unadapted_zones"] = {
                name: shapely.union_all([z.zone(name) for z in zones]) if zones else shapely.MultiPolygon()
                for name in ZONE_NAMES}
        return self._cache["unadapted_zones"]

    def interaction_polygons(self) -> dict[str, BaseGeometry]:
        return {space.name: space.interaction for space in self.object_spaces}

    def density_at(self, xs: Any, ys: Any) -> np.ndarray:
        """The people's density (groups summed, groups combined by max) at arbitrary points."""
        spaces = [ps.space for ps in self.person_spaces]
        return social_density(self.people, spaces, self.groups, xs, ys)

    def zone_at(self, x: float, y: float) -> str:
        """'intimate', 'personal', 'social' or 'public' at a point (from the density, not the grid)."""
        value = float(self.density_at(x, y))
        for name in ZONE_NAMES:
            if value >= self.params.zones.level(name):
                return name
        return "public"

    def layer(self, name: str) -> CostArray:
        """One layer alone on a free grid, for display: walls, bodies, footprints, people, objects."""
        free = np.full(self.spec.shape, self.params.grid.free_cost, dtype=self.cost.dtype)
        if name == "walls":
            return self.static
        if name == "people":
            return compose(free, (*self.zone_patches, *self.prediction_patches))
        if name == "objects":
            return compose(free, self.interaction_patches)
        raise ValueError(f"unknown layer {name!r}; expected walls, people or objects")

    def time_costs(self, cruise_speed_mps: float, *, time_step_s: float = 1.0, horizon_factor: float = 3.0,
                   incremental: IncrementalTimeCosts | None = None) -> TimeCosts | None:
        """``people_cost`` with the interaction spaces priced at arrival time (None without any): bins
        of ``time_step_s``, covering trips up to ``horizon_factor`` x (width + height) of the map.
        With ``incremental`` (a replanner's), that builder's grid updated from the map it built
        before (incremental.py: the same values), valid until its next use and not cached here."""
        if not any(m is not None for m in self.interaction_cells):
            return None
        key = ("time_costs", cruise_speed_mps, time_step_s, horizon_factor)
        if incremental is None and key in self._cache:
            return self._cache[key]
        by_object: dict[str, list[ActivityWindow]] = {}
        for window in self.activities:
            by_object.setdefault(window.object, []).append(window)
        windows = [by_object.get(o.name, ()) for o in self.objects]
        forbidden = [o.forbidden_while_active for o in self.objects]
        chron = self.params.chronemics

        def profiles(times: np.ndarray) -> np.ndarray:
            return interaction_cost_profiles(times, windows, chron, forbidden)

        xmin, ymin, xmax, ymax = self.spec.bounds
        horizon = horizon_factor * ((xmax - xmin) + (ymax - ymin))
        timing = (self.t_s, cruise_speed_mps, self.spec.resolution, time_step_s, horizon)
        if incremental is not None:
            return incremental.time_costs(self.static, self.people_layers, self.interaction_cells, profiles, *timing)
        cached = "people_cost" in self._cache
        base = self.people_cost if cached else compose(self.static, self.people_layers)
        self._cache[key] = time_costs(base, self.interaction_cells, profiles, *timing, in_place=not cached)
        return self._cache[key]


def _check_unique(kind: str, names: Sequence[str]) -> None:
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise SocialMapInputError(f"duplicate {kind} name {name!r}")
        seen.add(name)


def _static_key(bounds: Sequence[float], walls: Sequence[Wall], rooms: Sequence[Room], params: SocialMapParams,
                occupancy: OccupancyLayer | None) -> tuple[Any, ...]:
    key = (tuple(bounds), tuple(walls), tuple(rooms), params.grid.resolution_m, params.grid.robot_radius_m,
           params.grid.free_cost)
    return key if occupancy is None else (*key, occupancy.key)


def build_static_map(bounds: Sequence[float], walls: Sequence[Wall], rooms: Sequence[Room] = (),
                     params: SocialMapParams | None = None, *, occupancy: OccupancyLayer | None = None) -> StaticMap:
    """Rasterise the building once: walls (polylines and a building map's wall cells, ``occupancy``)
    inflated by the robot radius, outside the rooms blocked."""
    params = params or SocialMapParams()
    spec = GridSpec.from_bounds(bounds, params.grid.resolution_m)
    return StaticMap(spec=spec, grid=static_grid(spec, walls, rooms, params.grid, occupancy),
                     walls=walls_geometry(walls), key=_static_key(bounds, walls, rooms, params, occupancy),
                     occupancy=occupancy)


def build_social_map(bounds: Sequence[float], walls: Sequence[Wall], people: Sequence[Person],
                     objects: Sequence[SocialObject], activities: Sequence[ActivityWindow], t_s: float,
                     params: SocialMapParams | None = None, *, rooms: Sequence[Room] = (),
                     static: StaticMap | None = None, occupancy: OccupancyLayer | None = None) -> SocialMap:
    """Compose the social map at time ``t_s`` (seconds since local midnight).

    Pass ``static`` (from build_static_map with the same bounds, walls, rooms, grid params and
    ``occupancy``) to skip rasterising the building on every rebuild; a mismatching one is an error."""
    params = params or SocialMapParams()
    if not math.isfinite(t_s):
        raise SocialMapInputError(f"t_s must be finite, got {t_s!r}")
    _check_unique("person", [p.name for p in people])
    _check_unique("object", [o.name for o in objects])
    if static is None:
        static = build_static_map(bounds, walls, rooms, params, occupancy=occupancy)
    elif static.key != _static_key(bounds, walls, rooms, params, occupancy):
        raise SocialMapInputError("static map was built for other bounds, walls, rooms, building map or grid parameters")
    spec = static.spec
    grid_params = params.grid
    people = tuple(people)
    objects = tuple(objects)

    # People: role-scaled spaces (a walker's oriented along their motion and stretched ahead,
    # motion.py), adapted to walls, grouped, densities on windows, cost bands.
    scales = [role_scale(p, params.roles) for p in people]
    rest_spaces = [PersonalSpace.from_params(params.personal_space, scale) for scale in scales]
    people = tuple(oriented(p, params.motion) for p in people)
    base_spaces = [stretched(space, p, scale, params.motion) for space, p, scale in zip(rest_spaces, people, scales,
                                                                                       strict=True)]
    adaptations = adapt_spaces(people, base_spaces, static.walls, params.zones.level(params.adaptive.zone),
                               params.adaptive.robot_diameter_m or 2.0 * grid_params.robot_radius_m, params.adaptive,
                               occupancy=static.occupancy)
    spaces = [a.space for a in adaptations]
    groups = group_people(people, spaces, params.groups)

    # Objects: polygons, R(t_s), footprints and interaction cells.
    known = {o.name for o in objects}
    matched = tuple(a for a in activities if a.object in known)
    unmatched = tuple(a for a in activities if a.object not in known)
    geometries: list[ObjectGeometry] = [object_geometry(o) for o in objects]
    object_spaces = []
    owned = [[a for a in matched if a.object == obj.name] for obj in objects]
    rs = r_profiles(np.array([t_s]), owned, params.chronemics)[:, 0]   # R(t_s) of every object at once
    for obj, geometry, own, r in zip(objects, geometries, owned, rs.tolist(), strict=True):
        active = is_active(t_s, own)
        forbidden = active and obj.forbidden_while_active
        object_spaces.append(ObjectSpace(name=obj.name, kind=obj.kind, footprint=geometry.footprint,
                                         interaction=geometry.interaction, r=r, band=r_band(r, params.chronemics),
                                         active=active, forbidden=forbidden,
                                         cost=math.inf if forbidden else r))
    masks = interaction_masks(spec, objects, geometries)

    inflate = grid_params.robot_radius_m if grid_params.inflate_footprints else 0.0
    obstacles = (*footprint_patches(spec, objects, geometries, inflate),
                 *body_patches(spec, people, grid_params.person_radius_m + grid_params.robot_radius_m))
    zone_costs = zone_patches(spec, people, spaces, groups, params.zones, grid_params.social_cost,
                              grid_params.personal_cost)
    predicted = [(found, space, p.theta) for p, space, found in
                 zip(people, rest_spaces, predict_many(people, params.motion, static.walls), strict=True)
                 if found is not None]
    ahead = prediction_patches(spec, predicted, params.zones, grid_params.social_cost, grid_params.personal_cost)
    return SocialMap(spec=spec, params=params, t_s=float(t_s), people=people, objects=objects,
                     activities=matched, unmatched_activities=unmatched,
                     person_spaces=tuple(PersonSpace(p.name, a.space, a) for p, a in zip(people, adaptations,
                                                                                          strict=True)),
                     groups=tuple(groups), object_spaces=tuple(object_spaces), static=static.grid,
                     obstacle_patches=obstacles, zone_patches=tuple(zone_costs),
                     interaction_patches=tuple(interaction_patches(masks, [s.cost for s in object_spaces])),
                     interaction_cells=tuple(masks),
                     predictions=tuple(found for found, _, _ in predicted), prediction_patches=tuple(ahead))

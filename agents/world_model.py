"""Translate between the three views of the world: scene file, DSR graph, social-map inputs.

Why one module: the object recognition agent writes objects into the DSR, the social navigation
agent reads them back, the simulator needs their footprints and the offline tools (`chronav
path`, metrics) read the scene directly.  If each did its own conversion, a shape parameter
renamed in one place would silently change the robot's behaviour in another.
"""

from __future__ import annotations

from typing import Any

from shapely.geometry import Polygon

from agents.social_navigation.objects import posed_polygon
from agents.social_navigation.types import (
    ActivityWindow,
    Person,
    Room,
    Shape,
    SocialObject,
    Wall,
    shape_from_spec,
)
from scenes.model import Scene
from scenes.motion import people_at

# Clearance the navigation keeps beyond the robot's body when planning (it cuts corners a little
# when following a path); goal poses chosen by the executive respect the same margin.
PLANNING_MARGIN_M = 0.15

SHAPE_DIMS: dict[str, tuple[str, ...]] = {
    "rectangle": ("length", "width", "offset"),
    "circle": ("radius",),
    "trapezoid": ("height", "near_width", "far_width"),
}


# ----------------------------------------------------------------------------- scene -> social map
def scene_walls(scene: Scene) -> list[Wall]:
    return [Wall(points=tuple(map(tuple, wall)), name=f"wall{i}") for i, wall in enumerate(scene.walls)]


def scene_rooms(scene: Scene) -> list[Room]:
    return [Room(name=room.name, polygon=tuple(map(tuple, room.polygon))) for room in scene.rooms]


def scene_objects(scene: Scene) -> list[SocialObject]:
    return [SocialObject(name=o.name, kind=o.kind, x=o.pose.x, y=o.pose.y, theta=o.pose.theta,
                         footprint=shape_from_spec(o.footprint, f"object {o.name!r} footprint"),
                         interaction=shape_from_spec(o.interaction, f"object {o.name!r} interaction"),
                         forbidden_while_active=o.forbidden_while_active) for o in scene.objects]


def scene_people(scene: Scene, t_s: float) -> list[Person]:
    """Ground-truth people at ``t_s``, with the scene's declared interactions."""
    declared = {p.name: tuple(p.interacting_with) for p in scene.people}
    return [Person(name=p.name, x=p.x, y=p.y, theta=p.theta, role=p.role, interacting_with=declared[p.name])
            for p in people_at(scene, t_s)]


def door_segment(scene: Scene, door_name: str) -> tuple[tuple[float, float], tuple[float, float]]:
    """The door leaf when closed: a segment across the opening, along the wall the two rooms share."""
    import shapely

    door = next(d for d in scene.doors if d.name == door_name)
    a, b = (shapely.Polygon(next(r.polygon for r in scene.rooms if r.name == name)) for name in door.between)
    shared = a.boundary.intersection(b.boundary)
    centre = shapely.Point(door.position)
    half = door.width / 2 + 0.05
    if shared.is_empty or shared.length == 0:
        return ((door.position[0] - half, door.position[1]), (door.position[0] + half, door.position[1]))
    along = shared.project(centre)
    p0 = shared.interpolate(max(0.0, along - 0.01))
    p1 = shared.interpolate(min(shared.length, along + 0.01))
    dx, dy = p1.x - p0.x, p1.y - p0.y
    norm = (dx * dx + dy * dy) ** 0.5 or 1.0
    ux, uy = dx / norm, dy / norm
    x, y = door.position
    return ((x - half * ux, y - half * uy), (x + half * ux, y + half * uy))


def closed_door_walls(scene: Scene, graph: Any) -> list[Wall]:
    """Closed doors in the DSR (``open`` false) as walls, for the map."""
    known = {d.name for d in scene.doors}
    return [Wall(points=door_segment(scene, node.name), name=f"door {node.name}")
            for node in graph.nodes_of_type("door") if node.attrs.get("open") is False and node.name in known]


def footprint_polygons(scene: Scene) -> list[Polygon]:
    return [posed_polygon(obj.footprint, obj.x, obj.y, obj.theta) for obj in scene_objects(scene)]


# ----------------------------------------------------------------------------- shapes <-> DSR attrs
def shape_attrs(prefix: str, shape: Shape) -> dict[str, Any]:
    """``{prefix}_shape`` (str) and ``{prefix}_dims`` (list of float, order in SHAPE_DIMS)."""
    return {f"{prefix}_shape": shape.shape,
            f"{prefix}_dims": [float(getattr(shape, dim)) for dim in SHAPE_DIMS[shape.shape]]}


def shape_from_attrs(prefix: str, attrs: dict[str, Any], where: str) -> Shape:
    kind = attrs.get(f"{prefix}_shape")
    dims = attrs.get(f"{prefix}_dims")
    if kind not in SHAPE_DIMS or not isinstance(dims, list) or len(dims) != len(SHAPE_DIMS[kind]):
        raise ValueError(f"{where}: attributes {prefix}_shape/{prefix}_dims are missing or malformed")
    return shape_from_spec({"shape": kind, **dict(zip(SHAPE_DIMS[kind], dims, strict=True))}, where)


def object_attrs(obj: Any) -> dict[str, Any]:
    """DSR attributes of a recognised scene object (pose goes on its RT edge)."""
    return {"kind": obj.kind, "forbidden_while_active": obj.forbidden_while_active,
            **shape_attrs("footprint", shape_from_spec(obj.footprint, obj.name)),
            **shape_attrs("interaction", shape_from_spec(obj.interaction, obj.name))}


# ----------------------------------------------------------------------------- DSR -> social map
def dsr_objects(graph: Any) -> list[SocialObject]:
    """Objects as the DSR holds them; malformed ones are skipped (the agent logs them)."""
    out: list[SocialObject] = []
    for node in graph.nodes_of_type("object"):
        try:
            x, y, theta = graph.world_pose(node.id)
            out.append(SocialObject(name=node.name, kind=str(node.attrs.get("kind", "object")), x=x, y=y,
                                    theta=theta, footprint=shape_from_attrs("footprint", node.attrs, node.name),
                                    interaction=shape_from_attrs("interaction", node.attrs, node.name),
                                    forbidden_while_active=bool(node.attrs.get("forbidden_while_active", False))))
        except (ValueError, KeyError, LookupError):
            continue
    return out


def dsr_people(graph: Any) -> list[Person]:
    out: list[Person] = []
    interacting: dict[int, list[str]] = {}
    for edge in graph.edges_of_type("interacting"):
        other = graph.get_node(edge.dst)
        if other is not None and other.type == "person":
            interacting.setdefault(edge.src, []).append(other.name)
    for node in graph.nodes_of_type("person"):
        try:
            x, y, theta = graph.world_pose(node.id)
        except (KeyError, LookupError, ValueError):
            continue
        out.append(Person(name=node.name, x=x, y=y, theta=theta, role=str(node.attrs.get("role", "resident")),
                          interacting_with=tuple(interacting.get(node.id, ()))))
    return out


def dsr_activity_windows(graph: Any) -> list[ActivityWindow]:
    out: list[ActivityWindow] = []
    for node in graph.nodes_of_type("activity"):
        attrs = node.attrs
        try:
            out.append(ActivityWindow(object=str(attrs["object"]), start_s=float(attrs["start_s"]),
                                      end_s=float(attrs["end_s"]), cancelled=attrs.get("state") == "cancelled"))
        except (KeyError, ValueError, TypeError):
            continue
    return out


__all__ = ["closed_door_walls", "door_segment", "dsr_activity_windows", "dsr_objects", "dsr_people",
           "footprint_polygons", "object_attrs", "scene_objects", "scene_people",
           "scene_rooms", "scene_walls", "shape_attrs", "shape_from_attrs"]

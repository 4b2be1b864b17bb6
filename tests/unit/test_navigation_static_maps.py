"""The navigation keeps a bounded number of static maps (issue 41: bounded by design).

A static map is built per (rooms the route is confined to, closed doors); a day's missions take
ever other routes and the doors open and close, and each kept map holds its grids (0.4 MB for
center_day).  Kept unbounded, the navigation grew with each new route for as long as it lived."""

from __future__ import annotations

import itertools

from agents.world.navigation import STATIC_MAPS_KEPT, NavigationMaps
from scenes.loader import load_scene


def test_only_the_most_recently_used_static_maps_are_kept() -> None:
    scene = load_scene("center_day").scene
    nav = NavigationMaps.for_scene(scene)
    rooms = [room.name for room in scene.rooms]
    routes = [("corridor", *others) for n in (1, 2) for others in itertools.combinations(rooms[1:], n)]
    assert len(routes) > 2 * STATIC_MAPS_KEPT
    first = nav.static(routes[0])
    for route in routes[1:]:
        nav.static(route)
        assert nav.static(routes[0]) is first      # in use all along: kept, not rebuilt
    assert len(nav._statics) == STATIC_MAPS_KEPT
    rebuilt = nav.static(routes[1])                 # long unused: built again, and the same map
    assert (rebuilt.grid == NavigationMaps.for_scene(scene).static(routes[1]).grid).all()

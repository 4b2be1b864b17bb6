"""The time-dependent social map (the costmap): people's spaces, groups, objects' interaction spaces,
layers, the arrival-time cost table and the Nav2 exporter.

A library of pure functions on numpy/shapely data (no Zenoh, no Rerun) shared by the social
navigation agent, the offline tools and the tests.  Planning is agents.lib.planning, the elastic
band and control law agents.lib.control, the metrics agents.lib.metrics.  Import submodules
directly: this package imports nothing heavy (numba) on purpose.
"""

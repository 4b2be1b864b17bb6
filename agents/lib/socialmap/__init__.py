"""Time-dependent social mapping, global planning, elastic band, control and metrics.

A library of pure functions on numpy/shapely data (no Zenoh, no Rerun) shared by the social
navigation agent, the offline tools and the tests; the agent itself is ``agent.py``
(python -m agents.social_navigation).  Import submodules directly: this package imports nothing
heavy (numba) on purpose.
"""

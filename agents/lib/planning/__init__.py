"""Global planning on the social map: the planners, the grid search (A*/Dijkstra) and replanning.

Import submodules directly: this package imports nothing heavy (numba) on purpose.
"""

"""The benchmarks: one script per area, each printing ONE flat JSON object (units in the key names).

Run one as a script or a module, from the repository root:
``.venv/bin/python tools/bench/bench_dsr.py`` or ``.venv/bin/python -m tools.bench.bench_dsr``.
``make bench`` runs the quick set; README.md ("Benchmarks") lists them all.  Speed goals are
measured here, never by timed asserts in the tests.
"""

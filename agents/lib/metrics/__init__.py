"""Navigation quality metrics of a run: the catalogue (names, units, sources), the seeds' path
metrics and the metrics among moving people.
"""

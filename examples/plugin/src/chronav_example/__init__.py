"""Example chronav plug-ins, one file each: planner.py, controller.py, predictor.py, metric.py, note_taker.py (an agent).

Each is registered in this package's pyproject.toml under a ``chronav.*`` entry point group;
chronav imports nothing of this package until a run or ``chronav plugins`` asks for it.
"""

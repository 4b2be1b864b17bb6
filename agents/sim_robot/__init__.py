"""The simulated robot: body, laser, world and sim clock (python -m agents.sim_robot)."""

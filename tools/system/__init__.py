"""A launched system: its processes, its run directory and credentials, how commands join it, what the operator sees."""

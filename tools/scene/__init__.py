"""Scene files and building maps: `chronav scene check`, `chronav scene from-map`, `chronav map export`."""

"""The world model: from a scene and its scripted events to the world at a time, and that world in the DSR."""

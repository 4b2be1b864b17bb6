"""Offline planning questions, no processes: `chronav path`, `chronav metrics`, `chronav grammar check`, `chronav plan`, the gain tuner."""

"""What every chronav agent process shares: configuration, the run loop, clock and recording."""

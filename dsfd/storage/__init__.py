"""Edge: files that hold dsfd's own state (calibration state, fitted parameters)."""

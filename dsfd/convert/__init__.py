"""Converters of third-party measured data sets to the measured-data CSV (dsfd.measured)."""

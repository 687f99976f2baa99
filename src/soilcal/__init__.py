"""soilcal: open calibration of discrete-element soil models."""

__version__ = "0.1.0"

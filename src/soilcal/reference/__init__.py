"""Reference engines: the same case run by LIGGGHTS, for parity checks of soilcal's engine."""

"""soilcal.optimise"""

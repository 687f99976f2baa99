"""soilcal.rsm"""

"""soilcal.doe"""

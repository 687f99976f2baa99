"""soilcal.dem"""

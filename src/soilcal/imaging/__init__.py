"""soilcal.imaging"""

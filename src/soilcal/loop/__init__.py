"""soilcal.loop"""

"""soilcal.config"""

"""soilcal.plots"""

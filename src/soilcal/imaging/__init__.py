"""soilcal.imaging: photos of soil heaps, drum frames and furrow sections.

* :mod:`soilcal.imaging.scenes`: the rendered scenes with the printed value behind each.
* :mod:`soilcal.imaging.render`: seeded renderer writing JPEGs and ``*.truth.json`` sidecars,
  and drum testers' grey, time-averaged, S-shaped frames of known central slope.
* :mod:`soilcal.imaging.measure`: pile angles relative to the plate line, furrow profile
  and area (scikit-image); reads only the pixels and the user-known scale length.
* :mod:`soilcal.imaging.drum`: drum frames (photos on a stand or testers' exports): drum from
  its rim, level from a plate, the user's roll or the image axes, sub-pixel interface,
  central-chord angle and S-shape measures.
* :mod:`soilcal.imaging.manifest`: ``resources/images/<soil>/manifest.yaml`` and group means.
* :mod:`soilcal.imaging.figures`: original / gray / binary / contour / fitted-line figures.
"""

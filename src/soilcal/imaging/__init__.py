"""soilcal.imaging: photos of soil heaps, drum frames and furrow sections.

* :mod:`soilcal.imaging.scenes`: the rendered scenes with the printed value behind each.
* :mod:`soilcal.imaging.render`: seeded renderer writing JPEGs and ``*.truth.json`` sidecars.
* :mod:`soilcal.imaging.measure`: pile/drum angles relative to the plate line, furrow profile
  and area (scikit-image); reads only the pixels and the user-known scale length.
* :mod:`soilcal.imaging.manifest`: ``resources/images/<soil>/manifest.yaml`` and group means.
* :mod:`soilcal.imaging.figures`: original / gray / binary / contour / fitted-line figures.
"""

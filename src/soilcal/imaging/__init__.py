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

import os as _os

# numpy asks the kernel for transparent huge pages (madvise) for every array of 4 MB or more,
# and a photo measurement makes many full-frame float arrays that live for milliseconds:
# faulting them in as huge pages costs more system time than they save (measuring the vineyard
# soil's photos: 7-9 s of system CPU with them, 2.6-3.7 s without, the same user CPU).  Off for
# a process that loads numpy through this package (the `soilcal image` commands and the
# workflow's photo jobs); a value given in the environment is kept, and a process that loaded
# numpy before this package keeps numpy's default.
_os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")

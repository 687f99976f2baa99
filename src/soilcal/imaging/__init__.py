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

#: the cue images a pile photo can be measured on (``channel`` of
#: :func:`soilcal.imaging.measure.measure_pile`; ``auto``, the default, lets the search choose
#: among them)
CUES = ("gray", "chroma", "lab_a", "lab_b", "saturation")
#: what ``channel`` accepts, as error messages name it
CHANNELS_EXPECTED = ", ".join(repr(c) for c in CUES) + " or 'auto'"


def huge_pages_off() -> None:
    """Turn numpy's transparent huge pages off in this process, for a photo measurement.

    numpy asks the kernel for transparent huge pages (madvise) for every array of 4 MB or more,
    and a photo measurement makes many full-frame float arrays that live for milliseconds:
    faulting them in as huge pages costs more system time than they save (``soilcal image soil``
    on the vineyard soil's photos: 7.2-9.0 s of system CPU with them, 2.1-2.3 s without, the
    same user CPU).  Called by the measurement entry points (the ``soilcal image`` commands,
    :func:`soilcal.imaging.manifest.measure_manifest`, which the workflow's photo jobs run); it
    changes this process only, not the environment its children inherit, and leaves numpy's
    setting alone where the environment gives ``NUMPY_MADVISE_HUGEPAGE`` (read by numpy as it
    loads).  numpy has no public call for it: this is the function numpy's own import uses."""
    import os

    if "NUMPY_MADVISE_HUGEPAGE" in os.environ:
        return
    from numpy._core import multiarray

    multiarray._set_madvise_hugepage(False)

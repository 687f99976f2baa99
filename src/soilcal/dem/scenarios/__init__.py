"""DEM scenarios of the papers' physical tests, each a module with a common interface.

Every scenario module defines:

* ``NAME``: the registry name (also the CLI name: ``soilcal scenario run NAME``);
* ``RESPONSES``: the names of every response a run reports; ``MEASURES``: those a soil's
  ``simulation`` block may measure (numeric results of the test, not diagnostics), and
  optionally ``measures(setup)``: the ones a given setup yields, and ``for_measures(setup,
  measures)``: the setup a run needs to yield ``measures`` (an estimator nobody asked for
  switched off; the measured numbers are the same).  Every scenario reports
  ``peak_overlap``, the largest overlap as a fraction of a radius: over the tool pass in
  the soil-bin scenarios (furrow, bulldozing, rotary), over the whole run (filling
  included) in the bench-top ones;
* ``setups()``: named setups from the papers (dicts of dimensions, speeds, durations, each
  number cited beside it in the module);
* ``validate(setup, preset, source, params=None)``: raises
  :class:`soilcal.errors.InputError` for bad geometry or impossible settings, before
  anything runs (``params``, the run's :class:`~soilcal.dem.scenarios.base.DemParams`, for
  checks that depend on them: the funnel load's volume at the soil density);
* ``run(setup, params, preset="quick", seed=0, threads=None, vtk_dir=None)``: returns a
  :class:`soilcal.dem.scenarios.base.Result`;
* optionally ``RESTARTABLE = True`` and a ``restart=None`` argument of ``run``: a
  :class:`soilcal.dem.restart.Restart` that the run resumes from and writes every few
  minutes, stepping through a :class:`soilcal.dem.restart.Progress` (every scenario here
  does).

``SCENARIOS`` maps names to modules; a module that cannot be imported (not present in this
installation) is skipped so that the others keep working.  It is built on first use: a DEM job
asks :func:`get` for its one scenario, which imports that module alone (each module registers
under its own module name), and the other scenarios' modules are not loaded.
"""

from __future__ import annotations

import importlib

_MODULES = (
    "repose",
    "drum",
    "incline",
    "compression",
    "furrow",
    "bulldozing",
    "rotary",
)


def _load(names):
    out = {}
    for mod in names:
        try:
            m = importlib.import_module(f"{__name__}.{mod}")
        except ModuleNotFoundError as exc:
            if exc.name == f"{__name__}.{mod}":
                continue
            raise
        names_in = getattr(m, "NAMES", None) or (m.NAME,)
        for nm in names_in:
            out[nm] = m
    return out


def _scenarios() -> dict:
    """:data:`SCENARIOS`, built (every scenario module imported) on its first use."""
    if "SCENARIOS" not in globals():
        globals()["SCENARIOS"] = _load(_MODULES)
    return globals()["SCENARIOS"]


def __getattr__(name):
    if name == "SCENARIOS":
        return _scenarios()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def measures_of(mod, setup: dict) -> tuple:
    """The responses a run of scenario module ``mod`` with ``setup`` yields to measure."""
    return tuple(mod.measures(setup)) if hasattr(mod, "measures") else tuple(mod.MEASURES)


def setup_for_measures(mod, setup: dict, measures) -> dict:
    """``setup`` as a run of ``mod`` that must yield ``measures`` needs it
    (``mod.for_measures``; unchanged for a scenario without it)."""
    return mod.for_measures(setup, tuple(measures)) if hasattr(mod, "for_measures") else setup


def get(name: str, source: str = "<input>"):
    """The scenario module called ``name`` (InputError listing the known names otherwise)."""
    from soilcal.errors import InputError

    if name in _MODULES:
        # that module alone (each registers under its own module name)
        found = _load((name,))
        if name in found:
            return found[name]
    scenarios = _scenarios()
    if name not in scenarios:
        raise InputError(source, "scenario", f"one of {', '.join(sorted(scenarios))}", name)
    return scenarios[name]

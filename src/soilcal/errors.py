"""Errors that carry the file, the field and what was expected.

Every bad input (config, photo, table, measurement, simulation setting) raises
:class:`InputError`, whose message reads::

    <file>: <field>: expected <expected>, got <got>

so a user sees in one line what to fix and where.
"""

from __future__ import annotations

from pathlib import Path


class SoilcalError(Exception):
    """Base class of all soilcal errors."""


#: what an error says a table cell held where it holds no value: the reader takes a blank cell
#: and the usual missing-value marks alike (NA, N/A, nan, null: pandas' ``na_values``)
EMPTY_CELL = "empty (a blank cell or a missing-value mark such as NA or nan)"


class InputError(SoilcalError, ValueError):
    """Bad user input: names the file, the field and what was expected."""

    def __init__(self, path: str | Path | None, field: str, expected: str, got: object = None,
                 note: str | None = None):
        self.path = str(path) if path is not None else "<input>"
        self.field = field
        self.expected = expected
        self.got = got
        self.note = note  # where to look next (e.g. a photo's diagnostic image), after the message
        msg = f"{self.path}: {field}: expected {expected}"
        if got is not None:
            msg += f", got {got!r}"
        if note:
            msg += f" ({note})"
        super().__init__(msg)


class SimulationError(SoilcalError, RuntimeError):
    """A DEM run that cannot continue (blow-up, NaN), naming the step and particle."""

"""soilcal.doe: Plackett-Burman and Box-Behnken designs, coding, row comparison and the
path of steepest ascent (see :mod:`soilcal.doe.designs` and :mod:`soilcal.doe.steepest`)."""

from soilcal.doe.designs import (
    PB_GENERATORS,
    ColumnMatch,
    RowComparison,
    actual_to_coded,
    box_behnken,
    coded_to_actual,
    is_orthogonal,
    match_columns,
    pb_runs,
    plackett_burman,
    plackett_burman_source,
    same_rows,
)
from soilcal.doe.steepest import steepest_ascent_path

__all__ = [
    "PB_GENERATORS",
    "ColumnMatch",
    "RowComparison",
    "actual_to_coded",
    "box_behnken",
    "coded_to_actual",
    "is_orthogonal",
    "match_columns",
    "pb_runs",
    "plackett_burman",
    "plackett_burman_source",
    "same_rows",
    "steepest_ascent_path",
]

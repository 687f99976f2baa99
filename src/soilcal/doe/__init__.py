"""soilcal.doe: Plackett-Burman and Box-Behnken designs, coding, row comparison, the
path of steepest ascent and the adaptive design (see :mod:`soilcal.doe.designs`,
:mod:`soilcal.doe.steepest` and :mod:`soilcal.doe.adaptive`, imported on use: it needs
scikit-learn)."""

from soilcal.doe.designs import (
    ON_BOUND,
    PB_GENERATORS,
    ColumnMatch,
    RowComparison,
    actual_to_coded,
    at_bound,
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
    "ON_BOUND",
    "PB_GENERATORS",
    "ColumnMatch",
    "RowComparison",
    "actual_to_coded",
    "at_bound",
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

"""Reading a published CSV table (:func:`read_table`): the stage and measured tables of a soil
and every table a job reads back.  Kept apart from :mod:`soilcal.config.load` (which re-exports
it) so that a job reading a table does not import the schema loader (jsonschema, yaml)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from soilcal.errors import InputError


def read_table(path: Path, text_columns=()) -> pd.DataFrame:
    """Read a published CSV table; a missing or unreadable file raises InputError.

    The columns named in ``text_columns`` (labels: a tool id, a revision; ``True``: every
    column, to write the table back as it was) keep each cell's text as the file writes it (``007`` stays ``"007"``, ``1.10`` stays ``"1.10"``, ``NA`` or
    ``null`` stays that word, not pandas' missing value: the measured tables' loader decides
    where it is a label, :func:`soilcal.config.measurements._missing_words`; an empty cell is
    missing); the other columns are parsed by pandas (numbers as numbers).

    The header's cells are stripped of surrounding spaces.  Refused, naming the file: a
    header that names a column twice, a header of one cell holding ``;`` (a
    semicolon-separated export, whose decimal commas would be split), and a row whose number
    of fields differs from the header's (named by its line: an unquoted decimal comma such as
    ``155,4`` adds a field, and in every row it would shift each column one to the left).
    Rows of empty fields only at the end of the table, such as the ``,,,,`` lines a
    spreadsheet's export leaves after the data, are not rows of the table; such a row between
    data rows is read as a row of empty cells (and refused where a value is required)."""
    import csv
    import io

    if not path.is_file():
        raise InputError(path, "<file>", "an existing CSV table", "no such file")
    try:
        text = path.read_bytes().decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as exc:
        raise InputError(path, "<file>", "a readable CSV table",
                         f"a byte that is not UTF-8 at offset {exc.start}") from None
    header, names, line, first = None, [], 1, 1
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        for rec in reader:
            start, line = line, reader.line_num + 1
            empty = all(not c.strip() for c in rec)
            if header is None:
                if len(rec) <= 1 and empty:
                    continue  # a blank line before the header, or one empty cell: skipped
                header, first = rec, start
                if len(rec) == 1 and ";" in rec[0]:
                    raise InputError(path, "<file>", "a comma-separated table with decimal points",
                                     "a table separated by ';'")
                names = [c.strip() for c in rec]
                for j, nm in enumerate(names):
                    if nm and nm in names[:j]:
                        raise InputError(path, f"column {nm}", "a column named once in the header",
                                         f"columns {names.index(nm) + 1} and {j + 1}")
            elif len(rec) != len(header) and not (empty and len(rec) <= len(header)):
                raise InputError(path, f"line {start}", f"{len(header)} fields, as many as the header",
                                 f"{len(rec)} fields")
    except csv.Error as exc:
        raise InputError(path, f"line {line}", "a readable CSV row", str(exc)) from None
    # pandas reads from the header line found above (it would take a line of one empty quoted
    # cell, "", for the header); every row's field count is checked above
    body = "".join(io.StringIO(text, newline="").readlines()[first - 1:])
    try:
        df = pd.read_csv(io.StringIO(body))
    except Exception as exc:  # pandas raises several types for bad CSV
        text = " ".join(str(exc).split())
        raise InputError(path, "<file>", "a readable CSV table", text or type(exc).__name__) from None
    if len(df.columns) == len(names):
        df.columns = [nm or str(c) for nm, c in zip(names, df.columns)]
    keep = list(df.columns) if text_columns is True else [c for c in text_columns if c in df.columns]
    if keep:
        # as written: pandas' default missing-value words (NA, N/A, null, None, nan, ...) are
        # a label's text there (a tool or day called NA); only an empty cell is missing
        as_text = pd.read_csv(io.StringIO(body), dtype=str, keep_default_na=False, na_values=[])
        as_text.columns = df.columns
        for c in keep:
            cells = as_text[c]
            df[c] = cells.where(cells.str.strip() != "", np.nan)
    filled = np.flatnonzero(df.notna().any(axis=1).to_numpy())
    return df.iloc[:filled[-1] + 1 if filled.size else 0]

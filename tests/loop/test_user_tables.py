"""Measured tables as a user writes them (an id column per row, two measured quantities per
row, few rows): the loop's diagnosis and verdict on residual tables built by hand, each
expected value following from the construction written here."""

from __future__ import annotations

import numpy as np
import pandas as pd

from soilcal.loop.diagnose import diagnose, ranking


def _two_measure_table(per_row, ids, tools):
    """Six conditions, each measured twice (horizontal and vertical force) with the same
    relative residual ``per_row[i]`` for both: a per-row disturbance (a stone, a ridge)."""
    rows = []
    for i, (r, rid, tool) in enumerate(zip(per_row, ids, tools), start=1):
        for m in ("horizontal_force_N", "vertical_force_N"):
            rows.append({"measurement": "draft", "row": i, "measure": m, "relative_residual": r,
                         "standardised_residual": 1.0, "cov:run_id": rid, "cov:tool": tool})
    return pd.DataFrame(rows)


def test_a_column_naming_each_row_is_not_a_group_the_residual_follows():
    # the rows differ (0.2, -0.1, ...) and both measures of a row agree: grouped by a label
    # that is unique per row, a one-way ANOVA would explain all of the residual (r2 = 1),
    # which says only that the rows differ from each other, not what they differ by
    per_row = [0.2, -0.1, 0.05, -0.15, 0.1, -0.1]
    res = _two_measure_table(per_row, ids=[f"r{i}" for i in range(1, 7)], tools=["T1", "T2", "T3"] * 2)
    diag = diagnose(res, {"run_id": "", "tool": "tool"})
    assert "run_id" not in set(diag["covariate"])
    # the tool, three rows a level in two conditions each, is still tested
    assert len(diag[(diag["covariate"] == "tool") & (diag["test"] == "group")]) == 1
    assert "run_id" not in set(ranking(diag)["covariate"])


def test_a_label_shared_by_rows_of_one_condition_only_is_still_no_group():
    # a numbered day per row written as text ("d1".."d6"), declared as the test day: each
    # day holds one condition, so its group test is the same row-by-row comparison
    per_row = [0.2, -0.1, 0.05, -0.15, 0.1, -0.1]
    res = _two_measure_table(per_row, ids=[f"d{i}" for i in range(1, 7)], tools=["T1", "T2", "T3"] * 2)
    diag = diagnose(res, {"run_id": "day", "tool": "tool"})
    assert "run_id" not in set(diag["covariate"])

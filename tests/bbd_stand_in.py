"""The 15-run Box-Behnken design of three factors (three centre points), coded, as a table
with a ``run`` column: the design of several tests' known-quadratic stand-ins."""

import itertools

import numpy as np
import pandas as pd


def box_behnken_3() -> tuple[pd.DataFrame, np.ndarray]:
    """(table with run, A, B, C, coded points as floats)."""
    rows = []
    for i, j in itertools.combinations(range(3), 2):
        for a, b in itertools.product((-1, 1), repeat=2):
            x = [0, 0, 0]
            x[i], x[j] = a, b
            rows.append(x)
    rows += [[0, 0, 0]] * 3
    x = np.array(rows, float)
    df = pd.DataFrame(x.astype(int), columns=["A", "B", "C"])
    df.insert(0, "run", np.arange(1, len(df) + 1))
    return df, x

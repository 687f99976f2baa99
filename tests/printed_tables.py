"""Printed design tables shared by several tests, as the extracted paper texts print them."""

import re

import numpy as np

# Qiu et al. 2022, Table 3, X1..X11 columns of runs 1..12, as the extracted text prints them
# (cells run together; "−1" and "1" tokens).
_CINNAMON_PB_TEXT = """
1−111−11−1−111−1
1−1−1−11−11111−1
11−1111−11−1−1−1
−11−111−1−1−1111
1−1111−11−1−1−11
−1−1−11−11111−11
−1−1−1−1−1−1−1−1−1−1−1
−1111−1−111−11−1
111−1−1−1−111−11
−1−11−111−11−111
11−1−1−111−1−111
−111−1111−11−1−1
"""
CINNAMON_PB = np.array(
    [[int(t) for t in re.findall(r"-?1", ln.replace("\u2212", "-"))] for ln in _CINNAMON_PB_TEXT.split()],
    dtype=float,
)

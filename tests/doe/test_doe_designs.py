"""Designs against printed tables and analytic properties.

Printed designs:
- Qiu et al., Agriculture 2022, 12, 1082 (cinnamon soil), Table 3: 12-run Plackett-Burman,
  columns X1..X11 (X8..X11 dummies).
- Vineyard soil paper (seed 003), Table 3: 12-run Plackett-Burman, factors A..H printed
  (the two dummy columns are not printed).
- Qiu et al. 2022, Table 6: 17-run Box-Behnken on A, B, C.
"""


import numpy as np
import pyDOE3
import pytest

from soilcal.doe import (
    ON_BOUND,
    PB_GENERATORS,
    actual_to_coded,
    at_bound,
    box_behnken,
    coded_to_actual,
    is_orthogonal,
    match_columns,
    pb_runs,
    plackett_burman,
    same_rows,
    steepest_ascent_path,
)
from soilcal.errors import InputError

from printed_tables import CINNAMON_PB  # noqa: E402  (Qiu et al. 2022, Table 3)

# Vineyard soil paper, Table 3, columns A..H of runs 1..12 as printed.
VINEYARD_PB = np.array(
    [
        [-1, -1, 1, -1, 1, 1, -1, 1],
        [1, -1, 1, 1, 1, -1, -1, -1],
        [1, 1, 1, -1, -1, -1, 1, -1],
        [1, -1, 1, 1, -1, 1, 1, 1],
        [1, -1, -1, -1, 1, -1, 1, 1],
        [1, 1, -1, -1, -1, 1, -1, 1],
        [-1, -1, -1, -1, -1, -1, -1, -1],
        [-1, -1, -1, 1, -1, 1, 1, -1],
        [-1, 1, -1, 1, 1, -1, 1, 1],
        [-1, 1, 1, 1, 1, -1, -1, 1],
        [-1, 1, 1, -1, -1, 1, 1, -1],
        [1, 1, -1, 1, 1, 1, -1, -1],
    ],
    dtype=float,
)

# Qiu et al. 2022, Table 6 (coded A, B, C), runs 1..17.
CINNAMON_BBD = np.array(
    [
        [-1, -1, 0], [1, -1, 0], [-1, 1, 0], [1, 1, 0],
        [-1, 0, -1], [1, 0, -1], [-1, 0, 1], [1, 0, 1],
        [0, -1, -1], [0, 1, -1], [0, -1, 1], [0, 1, 1],
        [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0],
    ],
    dtype=float,
)


def test_printed_tables_parsed_as_printed():
    assert CINNAMON_PB.shape == (12, 11)
    assert VINEYARD_PB.shape == (12, 8)


@pytest.mark.parametrize("n_columns,n_runs", [(3, 4), (4, 8), (7, 8), (8, 12), (11, 12), (15, 16), (19, 20), (23, 24), (24, 28)])
def test_pb_run_count(n_columns, n_runs):
    assert pb_runs(n_columns) == n_runs


@pytest.mark.parametrize("n_columns", [3, 7, 10, 11, 15, 19, 23, 31])
def test_pb_orthogonal_and_balanced(n_columns):
    d = plackett_burman(n_columns)
    n = pb_runs(n_columns)
    assert d.shape == (n, n_columns)
    assert set(np.unique(d)) == {-1.0, 1.0}
    np.testing.assert_array_equal(d.T @ d, n * np.eye(n_columns))
    np.testing.assert_array_equal(d.sum(axis=0), np.zeros(n_columns))


@pytest.mark.parametrize("n_runs", sorted(PB_GENERATORS))
def test_pb_cyclic_structure(n_runs):
    d = plackett_burman(n_runs - 1)
    gen = np.array([1.0 if c == "+" else -1.0 for c in PB_GENERATORS[n_runs]])
    np.testing.assert_array_equal(d[0], gen)
    for i in range(1, n_runs - 1):
        np.testing.assert_array_equal(d[i], np.roll(d[i - 1], 1))
    np.testing.assert_array_equal(d[-1], -np.ones(n_runs - 1))


def test_cinnamon_table3_is_pb12_up_to_column_order():
    """Table 3 is an orthogonal 12-run PB; its rows are the classic cyclic rows with the
    columns X7..X11 in a different order (X1..X6 coincide)."""
    gen = plackett_burman(11)
    assert is_orthogonal(CINNAMON_PB)
    assert not same_rows(gen, CINNAMON_PB).equal
    m = match_columns(gen, CINNAMON_PB, allow_sign_flip=False)
    assert m.found and not m.identity
    assert m.columns[:6] == [0, 1, 2, 3, 4, 5]
    assert same_rows(gen[:, m.columns], CINNAMON_PB).equal


def test_pydoe3_pb12_differs_from_classic_as_row_set():
    """pyDOE3's N=12 design has an all-plus row; only sign flips map it to the classic one."""
    classic = plackett_burman(11)
    h = np.asarray(pyDOE3.pbdesign(11), dtype=float)
    assert not same_rows(classic, h).equal
    assert not match_columns(classic, h, allow_sign_flip=False).found
    assert match_columns(classic, h, allow_sign_flip=True).found


def test_vineyard_table3_column_E_runs_10_11_swapped():
    """Printed A..H are the first 8 columns of the classic PB12 except column E of runs 10
    and 11, whose entries are interchanged (the printed E is then not orthogonal to D, F,
    G, H). With the two entries swapped back the rows equal the classic design; the ANOVA
    of Tables 4-5 is reproduced only with the corrected column (tests/rsm)."""
    gen = plackett_burman(10)[:, :8]
    assert not is_orthogonal(VINEYARD_PB)
    assert not match_columns(plackett_burman(10), VINEYARD_PB).found
    fixed = VINEYARD_PB.copy()
    fixed[[9, 10], 4] = fixed[[10, 9], 4]
    assert is_orthogonal(fixed)
    assert same_rows(gen, fixed).equal


def test_same_rows_multiset_semantics():
    a = np.array([[1, 2], [1, 2], [3, 4]])
    b = np.array([[3, 4], [1, 2], [1, 2]])
    assert same_rows(a, b).equal
    c = np.array([[3, 4], [3, 4], [1, 2]])
    r = same_rows(a, c)
    assert not r.equal
    assert r.only_in_a == [[1.0, 2.0]] and r.only_in_b == [[3.0, 4.0]]
    assert same_rows(a, a + 1e-12).equal


@pytest.mark.parametrize("k,centres,runs", [(3, 5, 17), (4, 5, 29)])
def test_bbd_run_counts(k, centres, runs):
    d = box_behnken(k, centres)
    assert d.shape == (runs, k)
    assert (np.abs(d).sum(axis=1) == 0).sum() == centres


def test_bbd_k3_equals_cinnamon_table6_rows():
    assert same_rows(box_behnken(3, 5), CINNAMON_BBD).equal


def test_coded_actual_round_trip_and_table6_levels():
    # Qiu et al. 2022 Sec. 3.3.2: A 0.08/0.11/0.14, B 0.24/0.38/0.52, C 0.42/0.54/0.66
    low, high = [0.08, 0.24, 0.42], [0.14, 0.52, 0.66]
    act = coded_to_actual(CINNAMON_BBD, low, high)
    np.testing.assert_allclose(act[0], [0.08, 0.24, 0.54])
    np.testing.assert_allclose(act[-1], [0.11, 0.38, 0.54])
    np.testing.assert_allclose(actual_to_coded(act, low, high), CINNAMON_BBD, atol=1e-12)
    rng = np.random.default_rng(1)
    x = rng.uniform(-2, 2, (50, 3))
    np.testing.assert_allclose(actual_to_coded(coded_to_actual(x, low, high), low, high), x, atol=1e-12)
    with pytest.raises(InputError):
        coded_to_actual(x, [0, 0], [1, 1])


def test_steepest_ascent_montgomery_example():
    """Montgomery (Design and Analysis of Experiments, Example 11.1): yhat = 40.44 +
    0.775 x1 + 0.325 x2, x1 = (time - 35)/5, x2 = (temp - 155)/5; base step 5 min of time
    gives Delta x1 = 1, Delta x2 = 0.325/0.775 = 0.42, i.e. 2 F per step."""
    path = steepest_ascent_path({"time": 0.775, "temp": 0.325}, {"time": 30, "temp": 150},
                                {"time": 40, "temp": 160}, base="time", base_step_actual=5, n_steps=12)
    np.testing.assert_allclose(path["time"], 35 + 5 * np.arange(13))
    np.testing.assert_allclose(path["temp"], 155 + 5 * 0.325 / 0.775 * np.arange(13))
    assert path.attrs["coded_step"]["time"] == pytest.approx(1.0)
    assert path.attrs["coded_step"]["temp"] == pytest.approx(0.4194, abs=1e-4)
    down = steepest_ascent_path({"time": 0.775, "temp": 0.325}, [30, 150], [40, 160], "time", 5, 2,
                                direction="descent")
    np.testing.assert_allclose(down["time"], [35, 30, 25])


def test_steepest_ascent_bad_base():
    with pytest.raises(InputError):
        steepest_ascent_path({"A": 1.0}, [0], [1], base="B", base_step_actual=0.1, n_steps=3)


@pytest.mark.parametrize("tol", [ON_BOUND, 0.04, 0.5])
def test_a_coded_level_is_at_a_bound_within_the_tolerance_and_not_beyond_it(tol):
    eps = 1e-9
    # at the tolerance, just inside it, on the bound and past it: at the bound
    for x in (-1.0 + tol, -1.0 + tol - eps, -1.0, -1.2):
        assert at_bound(x, "low", tol) is True and at_bound(-x, "high", tol) is True
    # just outside the tolerance: not
    assert at_bound(-1.0 + tol + eps, "low", tol) is False
    assert at_bound(1.0 - tol - eps, "high", tol) is False
    # the far bound is not this one
    assert at_bound(1.0, "low", tol) is False and at_bound(-1.0, "high", tol) is False
    # arrays element-wise
    x = np.array([-1.0, -1.0 + tol, -1.0 + tol + eps, 0.0, 1.0])
    assert at_bound(x, "low", tol).tolist() == [True, True, False, False, False]


def test_at_bound_default_tolerance_and_side_check():
    assert ON_BOUND == 1e-6
    assert at_bound(-1.0 + 0.9e-6, "low") and not at_bound(-1.0 + 1.1e-6, "low")
    assert at_bound(1.0 - 0.9e-6, "high") and not at_bound(1.0 - 1.1e-6, "high")
    with pytest.raises(InputError):
        at_bound(0.0, "middle")


def test_loading_the_designs_does_not_import_pydoe3():
    """pyDOE3 (its package import loads every design module of it) is imported where a
    Box-Behnken or a Hadamard Plackett-Burman design is built: the workflow's rule files,
    which import soilcal.chain (and with it soilcal.doe) at every start, do not pay for it."""
    import subprocess
    import sys

    code = ("import sys, soilcal.doe, soilcal.chain; print('pyDOE3' in sys.modules); "
            "soilcal.doe.box_behnken(3, 1); print('pyDOE3' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "True"]

"""A selection over more candidates after one over fewer, on the same rows (the loop's second
round, :func:`soilcal.loop.core.run_inprocess`), shares the models the first one fitted and
cross-validated (``select.forward``'s ``shared``): every step, score and choice must be those of
a selection made on its own, and the models it shares are not fitted again."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

from soilcal.loop import select as sl
from soilcal.loop.core import _Rounds

from test_few_conditions import _named_effect


def _same(a, b) -> bool:
    """Equal to the last bit (NaN equal to NaN), through Scores, dicts, lists and arrays."""
    if dataclasses.is_dataclass(a):
        return type(a) is type(b) and all(_same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a))
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, (float, np.ndarray, np.floating)):
        x, y = np.asarray(a, float), np.asarray(b, float)
        return x.shape == y.shape and x.tobytes() == y.tobytes()
    return a == b


def test_a_selection_sharing_the_first_rounds_models_is_the_one_of_its_own(monkeypatch):
    # twelve conditions whose values follow a trend and an all-positive share (100 (1 + 0.3 x)
    # (1 + 0.2 s), 1 % noise): a first selection over the trend alone, then one over both
    fits = []
    fit = sl.Model.fit
    monkeypatch.setattr(sl.Model, "fit", lambda self, *a, **k: fits.append(self) or fit(self, *a, **k))
    rng = np.random.default_rng(5)
    n = 12
    trend = np.linspace(-0.5, 0.5, n)
    rng.shuffle(trend)
    share = 0.6 + 0.4 * rng.uniform(0.0, 1.0, n)
    measured = 100.0 * (1 + 0.3 * trend) * (1 + 0.2 * share) * (1 + rng.normal(0.0, 0.01, n))
    obs = pd.DataFrame({"simulation": [f"s{i}" for i in range(n)], "measure": "F", "measured": measured})
    y0 = np.full(n, 100.0)
    A, P = _named_effect(trend, "A"), _named_effect(share, "P")

    alone = sl.forward(obs, y0, {"A": A, "P": P})
    fits_alone = len(fits)
    shared = {}
    sl.forward(obs, y0, {"A": A}, shared=shared)
    first = len(fits)
    both = sl.forward(obs, y0, {"A": A, "P": P}, shared=shared)
    assert len(fits) - first < fits_alone  # the models over A alone were not fitted again
    assert len(both.steps) == len(alone.steps) and both.chosen == alone.chosen
    for (step, names, s), (step_a, names_a, s_a) in zip(both.steps, alone.steps):
        assert (step, names) == (step_a, names_a)
        assert _same(s, s_a), (step, names)
    for f in ("chosen", "final", "forward_chosen", "uniform", "uniform_s", "uniform_ci", "beside_uniform", "with_scale",
              "judged", "held_back"):
        assert _same(getattr(both, f), getattr(alone, f)), f


def test_rounds_bound_to_one_residual_table_refuse_another():
    # the rounds' fits belong to the residual table they were made on: another table is refused
    # rather than given the first one's fits
    a = pd.DataFrame({"measured": [1.0]})
    b = a.copy()
    rounds = _Rounds()
    rounds.check(a)
    rounds.check(a)
    with pytest.raises(ValueError, match="another table"):
        rounds.check(b)

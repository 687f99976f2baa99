"""Every figure writes a non-blank PNG (150 dpi) and a PDF; bad input names its field."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.image import imread

from soilcal import plots
from soilcal.errors import InputError
from soilcal.optimise import pso_optimise


class Quad:
    """y = 10 + x1 - 2 x2 + x1 x2 + 3 x1^2 (coded), with made-up observations for diagnostics."""

    factors = ["A", "B", "C"]
    low = np.array([0.1, 0.2, 0.3])
    high = np.array([0.5, 0.6, 0.9])
    response = "angle"

    def __init__(self):
        from soilcal.doe import box_behnken

        self.X = box_behnken(3, 3)
        self.fitted = self.predict(self.X)
        rng = np.random.default_rng(0)
        self.observed = self.fitted + rng.normal(0, 0.2, len(self.fitted))
        self.residuals = self.observed - self.fitted
        n, p = len(self.X), 10
        self.leverage = np.full(n, p / n)
        s = np.sqrt(self.residuals @ self.residuals / (n - p))
        self.studentized_residuals = self.residuals / (s * np.sqrt(1 - self.leverage))
        self.cooks_distance = self.studentized_residuals**2 * self.leverage / (p * (1 - self.leverage))

    def predict(self, X):
        X = np.atleast_2d(X)
        return 10 + X[:, 0] - 2 * X[:, 1] + X[:, 0] * X[:, 1] + 3 * X[:, 0] ** 2


def _check(paths, min_w=300, min_h=200):
    png, pdf = paths
    assert png.suffix == ".png" and pdf.suffix == ".pdf"
    assert pdf.stat().st_size > 1000 and pdf.read_bytes()[:5] == b"%PDF-"
    img = imread(png)
    h, w = img.shape[:2]
    assert w >= min_w and h >= min_h
    assert float(img[..., :3].var()) > 1e-3  # not blank
    return img


def test_response_surface(tmp_path):
    m = Quad()
    img = _check(plots.response_surface(m, 0, 1, stem=tmp_path / "rs", design_points=m.X,
                                        labels={"A": ("rolling friction", "-"), "B": ("JKR energy", "J/m²")}))
    # two panels side by side at 150 dpi: wider than tall
    assert img.shape[1] > 1.8 * img.shape[0]


def test_response_surface_fixed_levels_and_label_list(tmp_path):
    m = Quad()
    _check(plots.response_surface(m, 2, 0, fixed_coded={"B": 0.5}, stem=tmp_path / "rs2",
                                  labels=["A: a (-)", "b (-)", ("c", "J/m²")]))


@pytest.mark.parametrize("i, j, field", [(0, 3, "j"), (-1, 1, "i"), (1, 1, "j"), (0.5, 1, "i")])
def test_response_surface_bad_index(tmp_path, i, j, field):
    with pytest.raises(InputError) as e:
        plots.response_surface(Quad(), i, j, stem=tmp_path / "bad")
    assert e.value.field == field
    assert not (tmp_path / "bad.png").exists()


def test_response_surface_bad_points_and_labels(tmp_path):
    with pytest.raises(InputError, match="design_points"):
        plots.response_surface(Quad(), 0, 1, stem=tmp_path / "b", design_points=np.zeros((3, 2)))
    with pytest.raises(InputError, match="labels"):
        plots.response_surface(Quad(), 0, 1, stem=tmp_path / "b", labels=["a"])


def test_factor_label():
    assert plots.factor_label("A", ("JKR surface energy", "J/m²")) == "A: JKR surface energy (J/m²)"
    assert plots.factor_label("B", "static friction (-)") == "B: static friction (-)"
    assert plots.factor_label("C") == "C"


def test_pareto_effects_and_t_values(tmp_path):
    eff = pd.DataFrame({"term": ["A", "B", "C"], "effect": [2.0, -1.0, 0.1], "F": [25.0, 9.0, 0.04]})
    t = plots.standardized_effects(eff)
    assert list(t["t"]) == pytest.approx([5.0, -3.0, 0.2])  # sign(effect) sqrt(F)
    eff.attrs["residual"] = {"df": 4}
    _check(plots.pareto_effects(eff, tmp_path / "pareto"))
    # from p-values: t = t_{p/2, df}; p of |t| = 2.776 at df 4 is 0.05
    t = plots.standardized_effects(pd.DataFrame({"term": ["A"], "effect": [-1.0], "p": [0.05]}), df_resid=4)
    assert t["t"].iloc[0] == pytest.approx(-2.776445, abs=1e-5)


def test_pareto_bad_input(tmp_path):
    eff = pd.DataFrame({"term": ["A"], "effect": [1.0], "F": [4.0]})
    with pytest.raises(InputError, match="df_resid"):
        plots.pareto_effects(eff, tmp_path / "p")
    with pytest.raises(InputError, match="effects"):
        plots.pareto_effects(pd.DataFrame({"term": ["A"], "coef": [1.0]}), tmp_path / "p", df_resid=3)


def test_steepest_ascent(tmp_path):
    df = pd.DataFrame({"step": [1, 2, 3, 4], "A": [0.1, 0.2, 0.3, 0.4], "B": [1.0, 2.0, 3.0, 4.0],
                       "angle": [20.0, 25.0, 28.0, 31.0]})
    _check(plots.steepest_ascent(df, ["A", "B"], "angle", 27.69, tmp_path / "sa"))
    _check(plots.steepest_ascent(df, ["A", "B"], "angle", None, tmp_path / "sa_nt"))
    with pytest.raises(InputError, match="missing"):
        plots.steepest_ascent(df, ["A", "Z"], "angle", 27.69, tmp_path / "x")


def test_predicted_vs_actual_and_residuals(tmp_path):
    m = Quad()
    _check(plots.predicted_vs_actual(m, tmp_path / "pva"))
    img = _check(plots.residual_diagnostics(m, tmp_path / "res"), min_w=1000, min_h=800)
    assert img.shape[0] > 0


def test_diagnostics_on_fitted_rsm(tmp_path):
    from soilcal.rsm import fit_response_surface

    m = Quad()
    data = pd.DataFrame(m.X, columns=["A", "B", "C"]).assign(angle=m.observed)
    fit = fit_response_surface(data, ["A", "B", "C"], "angle", m.low, m.high)
    _check(plots.predicted_vs_actual(fit, tmp_path / "pva"))
    _check(plots.residual_diagnostics(fit, tmp_path / "res"))
    _check(plots.response_surface(fit, 0, 2, stem=tmp_path / "rs", design_points=m.X))


def test_diagnostics_need_a_fitted_model(tmp_path):
    with pytest.raises(InputError, match="model"):
        plots.residual_diagnostics(object(), tmp_path / "r")
    with pytest.raises(InputError, match="model"):
        plots.predicted_vs_actual(object(), tmp_path / "r")


def test_convergence(tmp_path):
    r = pso_optimise(lambda X: np.sum(np.atleast_2d(X) ** 2, axis=1), [[-1, 1]] * 2, particles=10,
                     iterations=20, seed=0)
    _check(plots.convergence(r, tmp_path / "conv"))
    _check(plots.convergence({"0 %": r, "5 %": r.history * 2}, tmp_path / "conv2"))
    with pytest.raises(InputError, match="history"):
        plots.convergence(np.array([1.0, np.nan]), tmp_path / "c")


def test_stem_with_suffix_and_new_directory(tmp_path):
    png, pdf = plots.convergence(np.array([3.0, 2.0, 1.0]), tmp_path / "deep" / "dir" / "c.png")
    assert png == tmp_path / "deep" / "dir" / "c.png" and pdf.exists()

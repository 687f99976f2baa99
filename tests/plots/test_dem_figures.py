"""DEM verification figures write non-blank PNG + PDF; tool tables split into curves (numeric
covariate) and bars (categorical); the paper overlays on the Pareto chart and the steepest-ascent
path add artists and leave the default figure unchanged; bad input names the column."""

from __future__ import annotations

import io

import numpy as np
import pandas as pd
import pytest
from matplotlib.image import imread
from matplotlib.lines import Line2D

from soilcal import plots
from soilcal.errors import InputError
from soilcal.plots import dem, figures


def _check_files(paths, n_figures=1):
    assert len(paths) == 2 * n_figures
    assert sorted(p.suffix for p in paths) == [".pdf"] * n_figures + [".png"] * n_figures
    for p in paths:
        assert p.exists() and p.stat().st_size > 1000
        if p.suffix == ".pdf":
            assert p.read_bytes()[:5] == b"%PDF-"
        else:
            img = imread(p)
            assert img.shape[0] >= 200 and img.shape[1] >= 300
            assert float(img[..., :3].var()) > 1e-3  # not blank


def _png_bytes(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=60)
    return buf.getvalue()


# --------------------------------------------------------------------------- frames


PAPER = {"upper": {"static": (30.82, 0.65), "dynamic": (42.70, 0.12)}}  # printed simulated angle, error %


def vineyard_verification() -> pd.DataFrame:
    """Three layers x (static, dynamic) angle of repose; the paper prints simulated angles for
    the upper layer only; one dynamic target is a 'minimize' goal (NaN target)."""
    rows = []
    for case, (ts, td) in {"upper": (30.62, 42.75), "middle": (31.4, 40.2), "lower": (32.1, np.nan)}.items():
        for resp, t in (("static", ts), ("dynamic", td)):
            sim = (t if np.isfinite(t) else 38.0) * 1.01
            rows.append({
                "stage": "bbd", "case": case, "response": resp, "target_id": f"{case}_{resp}", "target": t,
                "target_source": "paper", "preset": "quick", "n": 3, "seeds": "1;2;3", "simulated_mean": sim,
                "simulated_sd": 0.4, "relative_error_percent": 1.0 if np.isfinite(t) else np.nan,
                "within_2_percent": bool(np.isfinite(t)), "predicted": sim, "predicted_minus_target": 0.1,
                "paper_simulated": PAPER.get(case, {}).get(resp, (np.nan, np.nan))[0],
                "paper_relative_error_percent": PAPER.get(case, {}).get(resp, (np.nan, np.nan))[1],
                "status": "ok", "note": "",
            })
    return pd.DataFrame(rows)


def rotary_tool() -> pd.DataFrame:
    """Torque at five rotor speeds; one measured value not printed, paper simulated for all."""
    speeds = [200, 250, 300, 350, 400]
    measured = [10.2, 11.5, np.nan, 14.1, 15.0]
    return pd.DataFrame({
        "measurement": "rotary", "row": range(5), "covariate": "rotor_speed_rpm",
        "covariate_value": [str(s) for s in speeds], "scenario": "field", "setup": "blade_IT245", "measure": "torque",
        "unit": "N m", "preset": "quick", "stage": "bbd", "case": "topsoil", "n": 2, "seeds": "1;2",
        "measured": measured, "measured_sd": [0.3, 0.4, np.nan, 0.5, np.nan],
        "simulated_mean": [10.0, 11.9, 12.8, 13.7, 15.4], "simulated_sd": [0.2, 0.3, 0.2, 0.4, 0.3],
        "relative_error_percent": [-1.96, 3.48, np.nan, -2.84, 2.67],
        "paper_simulated": [10.4, 11.2, 12.5, 13.9, 14.8], "paper_relative_error_percent": np.nan,
        "status": "ok", "note": "",
    })


def plate_tool() -> pd.DataFrame:
    """Draft force of four bulldozing plates; paper simulated printed for two of them."""
    plates = ["arc", "parabola", "bionic", "line"]
    return pd.DataFrame({
        "measurement": "bulldozing", "row": range(4), "covariate": "directrix", "covariate_value": plates,
        "scenario": "bin", "setup": "plate", "measure": "draft", "unit": "N", "preset": "quick", "stage": "ccd",
        "case": "clay", "n": 2, "seeds": "1;2", "measured": [120.0, 115.0, 98.0, 130.0], "measured_sd": np.nan,
        "simulated_mean": [118.0, 117.5, 101.0, 127.0], "simulated_sd": [3.0, 2.5, 2.0, 4.0],
        "relative_error_percent": [-1.67, 2.17, 3.06, -2.31], "paper_simulated": [121.0, np.nan, 99.0, np.nan],
        "paper_relative_error_percent": np.nan, "status": "ok", "note": "",
    })


def summary_table() -> pd.DataFrame:
    rows = []
    for soil, cases in {"vineyard": ["upper", "lower"], "clay_loam": ["ccd"], "sandy": ["bbd"]}.items():
        for case in cases:
            for resp, t, err in (("static", 30.0, 1.2), ("dynamic", 40.0, -0.8)):
                rows.append({"soil": soil, "stage": "bbd", "case": case, "response": resp, "target": t,
                             "simulated_mean": t * (1 + err / 100), "simulated_sd": 0.5,
                             "relative_error_percent": err, "within_2_percent": abs(err) <= 2})
    rows.append({"soil": "sandy", "stage": "bbd", "case": "bbd", "response": "porosity", "target": np.nan,
                 "simulated_mean": 0.41, "simulated_sd": 0.01, "relative_error_percent": np.nan,
                 "within_2_percent": False})
    return pd.DataFrame(rows)


# --------------------------------------------------------------------------- verification / summary


def test_verification_bars(tmp_path):
    df = vineyard_verification()
    paths = plots.verification_bars(df, tmp_path / "verification", title="vineyard")
    _check_files(paths)
    assert {p.name for p in paths} == {"verification.png", "verification.pdf"}


def test_verification_bars_draw_paper_where_printed_and_skip_nan_targets():
    df = vineyard_verification()
    fig = dem._verification_figure(df)
    ax = fig.axes[0]
    heights = sorted(round(b.get_height(), 6) for b in ax.patches)
    n_target = int(np.isfinite(df["target"]).sum())  # 5: the lower/dynamic target is NaN
    n_paper = int(np.isfinite(df["paper_simulated"]).sum())  # 2
    assert len(ax.patches) == n_target + len(df) + n_paper
    assert 30.82 in heights and 42.70 in heights
    texts = [t.get_text() for t in ax.texts]
    assert texts.count("1.00 %") == n_target and "0.65 %" in texts and "0.12 %" in texts
    # without the paper columns only targets and simulated bars are drawn
    fig = dem._verification_figure(df.drop(columns=["paper_simulated", "paper_relative_error_percent"]))
    assert len(fig.axes[0].patches) == n_target + len(df)


def test_verification_bars_string_cells_and_status():
    df = vineyard_verification().astype({"paper_simulated": object})
    df.loc[0, "paper_simulated"] = ""  # as read from an empty CSV cell kept as text
    df.loc[1, ["simulated_mean", "simulated_sd", "relative_error_percent"]] = np.nan
    df.loc[1, "status"] = "engine blew up at step 12"
    fig = dem._verification_figure(df)
    assert any("blew up" in t.get_text() for t in fig.axes[0].texts)


def test_verification_bars_name_the_round_and_the_paper_preset():
    df = vineyard_verification()
    extra = df.iloc[[0, 0]].copy()
    extra["round"] = [2, 1]
    extra["preset"] = ["quick", "paper"]
    df = pd.concat([df.assign(round=1), extra], ignore_index=True)
    labels = [t.get_text() for t in dem._verification_figure(df).axes[0].get_xticklabels()]
    assert labels[0] == "upper\nstatic"
    assert labels[-2] == "upper\nstatic\nround 2" and labels[-1] == "upper\nstatic\npaper preset"


def test_verification_axis_names_the_unit_the_rows_share_else_each_label_does():
    df = vineyard_verification().assign(unit="deg")
    fig = dem._verification_figure(df)
    assert fig.axes[0].get_ylabel() == "response (deg)"
    assert [t.get_text() for t in fig.axes[0].get_xticklabels()][0] == "upper\nstatic"
    df.loc[1, "unit"] = "mm"
    ax = dem._verification_figure(df).axes[0]
    assert ax.get_ylabel() == "response"
    labels = [t.get_text() for t in ax.get_xticklabels()]
    assert labels[0] == "upper\nstatic (deg)" and labels[1] == "upper\ndynamic (mm)"
    # a table without units (written before the column existed) keeps the bare axis
    assert dem._verification_figure(vineyard_verification()).axes[0].get_ylabel() == "response"


def test_summary_figure(tmp_path):
    df = summary_table()
    _check_files(plots.summary_figure(df, tmp_path / "summary"))
    fig = dem._summary_figure(df)
    ax = fig.axes[0]
    assert len(ax.get_yticklabels()) == len(df)
    # one legend entry per soil plus the acceptance band
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert set(legend) == {"±2 % acceptance", "vineyard", "clay_loam", "sandy"}
    # the band spans -2 .. 2
    band = [p for p in ax.patches if p.get_label() == "±2 % acceptance"][0]
    xs = band.get_window_extent().transformed(ax.transData.inverted()).intervalx
    assert min(xs) == pytest.approx(-2) and max(xs) == pytest.approx(2)
    # bars: one per finite relative error, error bar half-width 100 * sd / target
    bars = [p for p in ax.patches if p is not band]
    assert len(bars) == len(df) - 1
    assert sorted({round(b.get_width(), 6) for b in bars}) == [-0.8, 1.2]
    # the title is drawn whole inside the figure, whatever the row labels' width
    long = df.assign(case=["a case whose label is long enough to squeeze the axes"] * len(df))
    fig = dem._summary_figure(long)
    fig.canvas.draw()
    box = fig._suptitle.get_window_extent()
    assert box.x0 >= 0 and box.x1 <= fig.bbox.x1 and box.y1 <= fig.bbox.y1


# --------------------------------------------------------------------------- tools


def test_tool_curves_for_numeric_covariate(tmp_path):
    df = pd.concat([rotary_tool(), plate_tool()], ignore_index=True)
    paths = plots.tool_curves(df, tmp_path / "tool")
    _check_files(paths)
    assert {p.name for p in paths} == {"tool_rotary_torque.png", "tool_rotary_torque.pdf"}
    # the plate group is categorical: no curve for it
    assert not (tmp_path / "tool_bulldozing_draft.png").exists()


def test_tool_bars_for_categorical_covariate(tmp_path):
    df = pd.concat([rotary_tool(), plate_tool()], ignore_index=True)
    paths = plots.tool_bars(df, tmp_path / "tool")
    _check_files(paths)
    assert {p.name for p in paths} == {"tool_bulldozing_draft.png", "tool_bulldozing_draft.pdf"}
    assert not (tmp_path / "tool_rotary_torque.png").exists()
    # each kind on its own writes nothing for the other
    assert plots.tool_bars(rotary_tool(), tmp_path / "only") == []
    assert plots.tool_curves(plate_tool(), tmp_path / "only") == []


def test_tool_curve_figure_series():
    g = rotary_tool()
    fig = dem._tool_curve_figure(g, "rotary", "torque")
    ax = fig.axes[0]
    assert ax.get_xlabel() == "rotor_speed_rpm" and ax.get_ylabel() == "torque (N m)"
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    assert len(lines["measured"].get_xdata()) == 4  # the missing measured value is skipped
    assert len(lines["paper simulated"].get_xdata()) == 5
    assert lines["paper simulated"].get_linestyle() == "--"
    sim = [c for c in ax.containers if c.get_label() == "soilcal DEM (mean ± SD)"][0]
    assert list(sim.lines[0].get_xdata()) == [200, 250, 300, 350, 400]
    # without paper and measured columns only soilcal's line remains
    fig = dem._tool_curve_figure(g.drop(columns=["paper_simulated", "measured_sd"]).assign(measured=np.nan),
                                 "rotary", "torque")
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["soilcal DEM (mean ± SD)"]


def test_tool_bar_figure_bars_and_errors():
    g = plate_tool()
    fig = dem._tool_bar_figure(g, "bulldozing", "draft")
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["arc", "parabola", "bionic", "line"]
    assert len(ax.patches) == 4 + 4 + 2  # measured, soilcal, paper where printed
    assert [t.get_text() for t in ax.texts] == ["-1.67 %", "2.17 %", "3.06 %", "-2.31 %"]
    assert ax.get_ylabel() == "draft (N)"


def test_tool_bar_figure_labels_the_papers_error():
    # the paper's simulated 121 N against the measured 120 N is +0.83 %; 99 N against 98 N +1.02 %
    g = plate_tool().assign(paper_relative_error_percent=[0.83, np.nan, 1.02, np.nan])
    ax = dem._tool_bar_figure(g, "bulldozing", "draft").axes[0]
    texts = [t.get_text() for t in ax.texts]
    assert texts == ["-1.67 %", "0.83 %", "2.17 %", "3.06 %", "1.02 %", "-2.31 %"]
    paper_labels = [t for t in ax.texts if t.get_text() in ("0.83 %", "1.02 %")]
    assert all(t.get_color() == dem.C_PAPER for t in paper_labels)


def _overlapping_labels(fig) -> list[tuple[str, str]]:
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    boxes = [(t.get_text(), t.get_window_extent(r)) for ax in fig.axes for t in ax.texts]
    boxes += [("legend", ax.get_legend().get_window_extent(r)) for ax in fig.axes if ax.get_legend()]
    boxes += [("title", ax.title.get_window_extent(r)) for ax in fig.axes]
    page = fig.bbox
    outside = [name for name, b in boxes if b.x0 < page.x0 or b.x1 > page.x1 or b.y0 < page.y0 or b.y1 > page.y1]
    assert outside == []
    return [(a, b) for i, (a, ba) in enumerate(boxes) for b, bb in boxes[i + 1:] if ba.overlaps(bb)]


@pytest.mark.parametrize("rows", [4, 12])
def test_bar_labels_of_neighbouring_bars_do_not_overlap(rows):
    # soilcal's and the paper's bars of equal height side by side: the labels' drawn boxes must
    # not touch each other, the legend or the title (they read "-1.67 %0.83 %" when written
    # level across bars 0.26 wide) and must stay on the page
    g = pd.concat([plate_tool()] * (rows // 4), ignore_index=True)
    g = g.assign(covariate_value=[f"plate {i}" for i in range(len(g))],
                 simulated_mean=g["measured"], paper_simulated=g["measured"],
                 relative_error_percent=-11.67, paper_relative_error_percent=-10.83)
    assert _overlapping_labels(dem._tool_bar_figure(g, "bulldozing", "draft")) == []
    v = vineyard_verification()
    v = v.assign(simulated_mean=v["target"], paper_simulated=v["target"], simulated_sd=0.0,
                 relative_error_percent=-12.25, paper_relative_error_percent=-10.5)
    assert _overlapping_labels(dem._verification_figure(v)) == []


def test_case_labels_of_two_stages_with_long_names_do_not_run_together():
    # two stages, case and response ids of 25 characters: the x tick labels' drawn boxes must
    # not touch (the stage prefix made a 29-character line that ran into its neighbours' in a
    # 6.5 in figure of three groups)
    v = vineyard_verification().iloc[:3].copy()
    v["stage"] = ["soil-soil", "soil-soil", "soil-65mn"]
    v["case"] = v["response"] = ["accumulation_angle_" + s for s in ("first", "other", "65mn_x")]
    fig = dem._verification_figure(v)
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    boxes = [t.get_window_extent(r) for t in fig.axes[0].get_xticklabels() if t.get_text()]
    assert len(boxes) == 3
    assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:])


def test_tool_stem_sanitised(tmp_path):
    df = rotary_tool().assign(measurement="rotary tiller", measure="torque/N")
    paths = plots.tool_curves(df, tmp_path / "t")
    assert {p.name for p in paths} == {"t_rotary_tiller_torque_N.png", "t_rotary_tiller_torque_N.pdf"}


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize("func, frame, column", [
    (plots.verification_bars, vineyard_verification, "simulated_sd"),
    (plots.verification_bars, vineyard_verification, "target"),
    (plots.tool_curves, rotary_tool, "covariate_value"),
    (plots.tool_bars, plate_tool, "relative_error_percent"),
    (plots.summary_figure, summary_table, "soil"),
])
def test_missing_column_is_named(tmp_path, func, frame, column):
    with pytest.raises(InputError, match=column) as e:
        func(frame().drop(columns=[column]), tmp_path / "x")
    assert e.value.field == "df"
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("func, frame", [
    (plots.verification_bars, vineyard_verification), (plots.tool_curves, rotary_tool),
    (plots.tool_bars, plate_tool), (plots.summary_figure, summary_table),
])
def test_empty_frame(tmp_path, func, frame):
    with pytest.raises(InputError, match="at least one row"):
        func(frame().iloc[0:0], tmp_path / "x")
    with pytest.raises(InputError, match="DataFrame"):
        func([1, 2], tmp_path / "x")


# --------------------------------------------------------------------------- paper overlays


def _effects():
    eff = pd.DataFrame({"term": ["A", "B", "C", "AB"], "effect": [2.0, -1.0, 0.1, 0.5], "F": [25.0, 9.0, 0.04, 3.0]})
    eff.attrs["residual"] = {"df": 4}
    return eff


def test_pareto_reference_overlay(tmp_path):
    eff = _effects()
    ref = pd.DataFrame({"term": ["A", "B", "AB", "Z"], "t": [4.0, -6.5, np.nan, 9.0]})
    fig0 = figures._pareto_figure(eff, 0.05, True, None, None)
    fig1 = figures._pareto_figure(eff, 0.05, True, None, None, reference=ref, reference_label="Wang 2022")
    ax0, ax1 = fig0.axes[0], fig1.axes[0]
    assert len(ax1.get_lines()) == len(ax0.get_lines()) + 1
    mark = [ln for ln in ax1.get_lines() if ln.get_label() == "Wang 2022 |t|"][0]
    assert mark.get_marker() == "D"
    # A and B only (AB has no t, Z is not a term), at |t| and on the rows of the bars
    assert list(mark.get_xdata()) == [4.0, 6.5]
    rows = {lab.get_text(): y for lab, y in zip(ax1.get_yticklabels(), ax1.get_yticks())}
    ys = ax1.yaxis.convert_units(list(mark.get_ydata()))
    assert list(ys) == [rows["A"], rows["B"]]
    assert "Wang 2022 |t|" in [t.get_text() for t in ax1.get_legend().get_texts()]
    assert ax1.get_xlim()[1] >= 6.5  # axis widened to the paper's largest effect
    assert _png_bytes(fig0) != _png_bytes(fig1)
    _check_files(list(plots.pareto_effects(eff, tmp_path / "p", reference=ref)))


def test_pareto_reference_none_is_default():
    eff = _effects()
    a = _png_bytes(figures._pareto_figure(eff, 0.05, True, None, None))
    b = _png_bytes(figures._pareto_figure(eff, 0.05, True, None, None, reference=None))
    assert a == b
    # a reference sharing no term draws nothing more
    ref = pd.DataFrame({"term": ["Z"], "t": [3.0]})
    fig = figures._pareto_figure(eff, 0.05, True, None, None, reference=ref)
    assert all(ln.get_label() != "paper |t|" for ln in fig.axes[0].get_lines())


def test_pareto_reference_bad(tmp_path):
    with pytest.raises(InputError, match="reference") as e:
        plots.pareto_effects(_effects(), tmp_path / "p", reference=pd.DataFrame({"term": ["A"], "F": [2.0]}))
    assert "'t'" in str(e.value)


def _path():
    return pd.DataFrame({"step": [1, 2, 3, 4], "A": [0.1, 0.2, 0.3, 0.4], "B": [1.0, 2.0, 3.0, 4.0],
                         "angle": [20.0, 25.0, 28.0, 31.0]})


@pytest.mark.parametrize("target", [27.69, None])
def test_steepest_ascent_reference_overlay(tmp_path, target):
    df = _path()
    ref = pd.DataFrame({"step": [1, 2, 3, 4], "angle": [21.0, 24.5, np.nan, 30.0]})
    fig0 = figures._steepest_ascent_figure(df, ["A", "B"], "angle", target)
    fig1 = figures._steepest_ascent_figure(df, ["A", "B"], "angle", target, reference=ref, reference_label="Li 2021")
    lines = {ln.get_label(): ln for ln in fig1.axes[0].get_lines()}
    assert len(fig1.axes[0].get_lines()) == len(fig0.axes[0].get_lines()) + 1
    paper = lines["Li 2021: angle"]
    assert list(paper.get_xdata()) == [1, 2, 4] and list(paper.get_ydata()) == [21.0, 24.5, 30.0]
    assert paper.get_marker() != lines["angle"].get_marker() and paper.get_color() != lines["angle"].get_color()
    assert "Li 2021: angle" in [t.get_text() for t in fig1.axes[0].get_legend().get_texts()]
    assert _png_bytes(fig0) != _png_bytes(fig1)
    _check_files(list(plots.steepest_ascent(df, ["A", "B"], "angle", target, tmp_path / "sa", reference=ref)))


def test_steepest_ascent_reference_none_and_bad(tmp_path):
    df = _path()
    a = _png_bytes(figures._steepest_ascent_figure(df, ["A", "B"], "angle", 27.69))
    b = _png_bytes(figures._steepest_ascent_figure(df, ["A", "B"], "angle", 27.69, reference=None))
    assert a == b
    assert all(isinstance(ln, Line2D) for ln in figures._steepest_ascent_figure(df, ["A", "B"], "angle", 27.69)
               .axes[0].get_lines())
    with pytest.raises(InputError, match="reference") as e:
        plots.steepest_ascent(df, ["A", "B"], "angle", 27.69, tmp_path / "x",
                              reference=pd.DataFrame({"step": [1], "force": [2.0]}))
    assert "angle" in str(e.value)


def test_steepest_ascent_trend_line_marks_the_trend_s_step(tmp_path):
    """With the trend drawn, the error bars and the marked step are the trend's: a run at
    step 3 on the target by chance (28.0 vs 27.69) is not the one marked when the trend puts
    step 4 closer."""
    df = _path()
    trend = [22.0, 24.0, 26.0, 27.6]
    fig = figures._steepest_ascent_figure(df, ["A", "B"], "angle", 27.69, trend=trend)
    lines = {ln.get_label(): ln for ln in fig.axes[0].get_lines()}
    assert list(lines["trend through the runs"].get_ydata()) == trend
    bars = [p.get_height() for p in fig.axes[1].patches]
    np.testing.assert_allclose(bars, np.abs(np.array(trend) - 27.69) / 27.69 * 100, rtol=1e-12)
    marked = [t for t in fig.axes[0].texts if t.get_text().endswith("%")]
    assert len(marked) == 1 and marked[0].xy == (4, 27.6)
    with pytest.raises(InputError, match="trend"):
        figures._steepest_ascent_figure(df, ["A", "B"], "angle", 27.69, trend=[1.0, 2.0])
    _check_files(list(plots.steepest_ascent(df, ["A", "B"], "angle", 27.69, tmp_path / "tr", trend=trend)))

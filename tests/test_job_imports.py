"""What a workflow job loads before it works: every job is a fresh Python process, so a package
it imports without using it costs every job of its kind again (scipy.optimize about 0.5 s,
statsmodels about 1.2 s on the project's machines; the DEM design points are most of the jobs).
Each job kind's modules are imported in a fresh interpreter, as its script in workflow/scripts
does, and the heavy packages that kind never calls must stay unloaded.  A package a job does
call is imported where it is used: a missing one still stops the job with its name."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = ROOT / "workflow/scripts"
#: the scripts of the DEM jobs (one job per design point, tool condition, verification seed and
#: loop run), with every scenario module the jobs may run
DEM_SCRIPTS = ["dem_point", "tool_point", "verify_point"]
DEM_MODULES = "import soilcal.dem.scenarios, soilcal.dem.scenarios.compile, soilcal.chain.sources, soilcal.chain.verify"
#: heavy packages no DEM job calls on the workflow's scenarios' ordinary paths
NOT_FOR_DEM = ["scipy.optimize", "scipy.stats", "scipy.spatial", "scipy.sparse", "statsmodels", "matplotlib",
               "pymoo", "pyDOE3", "skimage"]


def _script_imports(name: str) -> str:
    """The top-level import statements of a workflow script, as its job runs them."""
    tree = ast.parse((SCRIPTS / f"{name}.py").read_text())
    return "\n".join(ast.unparse(n) for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom)))


def _run(code: str) -> str:
    """What a fresh interpreter prints running ``code`` with the package's sources first."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=ROOT)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def _loaded(code: str, modules: list[str]) -> list[str]:
    """Which of ``modules`` a fresh interpreter has loaded after running ``code``."""
    return _run(f"{code}\nimport sys\nprint(' '.join(m for m in {modules!r} if m in sys.modules))").split()


@pytest.mark.parametrize("script", DEM_SCRIPTS)
def test_a_dem_job_loads_no_fitting_plotting_or_root_finding_package(script):
    assert _loaded(_script_imports(script) + "\n" + DEM_MODULES, NOT_FOR_DEM) == []


#: every scenario module (soilcal.dem.scenarios._MODULES)
SCENARIO_MODULES = ["repose", "drum", "incline", "compression", "furrow", "bulldozing", "rotary"]


@pytest.mark.parametrize("name", SCENARIO_MODULES)
def test_a_dem_job_loads_its_own_scenario_and_no_config_schema(name):
    # a DEM job asks for its one scenario module (chain.sources.simulate: scenarios.get): the
    # other scenarios' modules stay unloaded, and so do the config loader's jsonschema and the
    # loader itself (the job gets its spec as plain data)
    code = _script_imports("dem_point") + f"\nfrom soilcal.dem.scenarios import get\nget({name!r})"
    others = [f"soilcal.dem.scenarios.{m}" for m in SCENARIO_MODULES if m != name]
    own = f"soilcal.dem.scenarios.{name}"
    assert _loaded(code, [own] + others + ["soilcal.config.load", "jsonschema"]) == [own]


def test_the_scenario_registry_still_lists_every_scenario():
    out = _run("from soilcal.dem import scenarios\nprint(' '.join(sorted(scenarios.SCENARIOS)))")
    assert out.split() == sorted(SCENARIO_MODULES)


def test_a_design_job_loads_no_response_surface_fit():
    # the design jobs read the stage and build its design (pyDOE3 on use); the fits are the
    # regression jobs'
    code = _script_imports("design") + "\nimport soilcal.chain.stage, soilcal.chain.derive"
    assert _loaded(code, ["statsmodels", "scipy.stats", "scipy.optimize", "matplotlib"]) == []


@pytest.mark.parametrize("script", ["regression", "optimum", "figures", "errata"])
def test_a_job_reading_its_stage_table_loads_no_config_schema(script):
    # the regression, optimum and figure jobs read their stage's response table through the
    # published tables' reader (soilcal.config.tables): the soil's config loader, its schema
    # checker and the YAML parser stay unloaded (the job gets its stage as plain data)
    code = (_script_imports(script) + "\nfrom soilcal.chain.files import _table\n"
            "assert len(_table('resources/published/cinnamon-soil/bbd.csv'))")
    assert _loaded(code, ["soilcal.config.load", "jsonschema", "yaml"]) == []


def test_a_paths_optimum_and_figure_jobs_load_no_surface_fit_or_optimiser():
    # a steepest-ascent path's optimum job chooses its step and its figure job draws its runs
    # (the cinnamon soil's printed path, as the published replay runs it): neither loads the
    # response-surface fits, statsmodels' whole model catalogue or the optimisers
    code = (_script_imports("optimum") + "\n" + _script_imports("figures") + "\n"
            "import tempfile, yaml\nfrom pathlib import Path\nfrom soilcal.chain import derive\n"
            "from soilcal.chain.files import write_figures\n"
            "soil = yaml.safe_load(open('config/soils/cinnamon-soil.yaml'))\n"
            "st = derive.published_stage({'stages': soil['stages']}, 'steepest')\n"
            "table = 'resources/published/cinnamon-soil/steepest.csv'\n"
            "out = Path(tempfile.mkdtemp())\n"
            "write_optimum(st, table, soil['targets'], soil['seed'], out / 'optimum.csv')\n"
            "assert (out / 'optimum.csv').stat().st_size\n"
            "assert write_figures('steepest', st, table, soil['targets'], out / 'figures', soil['parameters'])\n")
    assert _loaded(code, ["soilcal.rsm", "statsmodels.api", "scipy.optimize", "soilcal.optimise"]) == []


def test_a_paths_trend_is_fitted_without_statsmodels_whole_catalogue():
    # the trend through a path's runs (the DEM path's choice of step, its optimum and figure
    # jobs) is one OLS fit: statsmodels' regression module, not statsmodels.api
    code = ("from soilcal.doe.steepest import path_trend\n"
            "t = path_trend([1, 2, 3, 4, 5, 6], [20.0, 22.5, 24.1, 27.0, 28.2, 31.0])\n"
            "assert t['degree'] == 1 and t['n'] == 6\n")
    assert _loaded(code, ["statsmodels.regression.linear_model", "statsmodels.api"]) == [
        "statsmodels.regression.linear_model"]


@pytest.mark.parametrize("script", ["loop_diagnose", "loop_more", "loop_select"])
def test_a_loop_job_loads_no_root_finder_before_it_fits(script):
    assert _loaded(_script_imports(script), ["scipy.optimize", "scipy.stats", "statsmodels", "matplotlib"]) == []


def test_the_dem_summary_figures_load_no_statistics():
    assert _loaded(_script_imports("dem_figures"), ["scipy.stats", "statsmodels"]) == []


def test_the_workflow_plans_its_jobs_without_statistics_or_root_finding():
    # snakemake's own process imports the rules' modules at every invocation (each run, each dry
    # run) and asks them for the jobs' inputs; the adaptive design's fits and proposals, which
    # call scipy's statistics, optimiser and sequences, run in its jobs only
    smk = (ROOT / "workflow/rules/common.smk").read_text()
    imports = "\n".join(line for line in smk.splitlines() if line.startswith(("import ", "from ")))
    assert "soilcal.chain import adaptive" in imports
    assert _loaded(imports, ["scipy.stats", "scipy.optimize", "statsmodels", "matplotlib"]) == []


def test_the_workflow_checks_every_soils_photos_without_the_image_libraries():
    # snakemake's own process loads every soil at each invocation and checks its photo
    # manifest, drum frames' options included (the vineyard soil's); measuring the photos,
    # which needs scikit-image and scipy's image filters, is the image_measure job's
    code = ("import yaml\nfrom soilcal.config import load_workflow_config\n"
            "soils = load_workflow_config(yaml.safe_load(open('config/config.yaml')))\n"
            "assert any(s.manifest is not None and any(p['kind'] == 'drum' for p in s.manifest['photos'])"
            " for s in soils.values())")
    assert _loaded(code, ["skimage", "scipy.ndimage", "soilcal.imaging.drum", "soilcal.imaging.measure"]) == []


def test_a_missing_package_still_stops_the_call_that_needs_it_with_its_name():
    # scipy.sparse made unimportable: welding a mesh (which needs its graph) fails naming it,
    # an import that needs nothing of it still works
    code = ("import sys\nsys.modules['scipy.sparse'] = None\nimport numpy as np\n"
            "from soilcal.dem import stl, engine\n"
            "soup = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], float)\n"
            "try:\n    stl.weld(soup, weld_tol=1e-6)\nexcept ImportError as exc:\n    print('refused:', exc)\n")
    out = _run(code)
    assert out.startswith("refused:") and "scipy.sparse" in out

"""The documentation site (mkdocs.yml, docs/): it builds in strict mode (a broken
link, a missing page or a failing cross-reference fails it), the tutorial notebook
executed into it; every public module is in the API reference and every public
class, function and method has a docstring."""
import importlib
import inspect
import os
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import dacph_drake

ROOT = Path(__file__).resolve().parents[1]


def _public_modules():
    return [info.name for info in pkgutil.walk_packages(dacph_drake.__path__,
                                                        "dacph_drake.")
            if not info.name.endswith("__main__")]


def test_every_public_module_is_in_the_api_reference():
    documented = set()
    for page in (ROOT / "docs" / "reference").glob("*.md"):
        documented |= set(re.findall(r"^::: (\S+)$", page.read_text(), re.M))
    assert sorted(set(_public_modules()) - documented) == []


def test_every_public_symbol_has_a_docstring():
    missing = []
    for name in _public_modules():
        module = importlib.import_module(name)
        if not (module.__doc__ or "").strip():
            missing.append(name)
        for symbol, obj in vars(module).items():
            if symbol.startswith("_") or getattr(obj, "__module__", None) != name:
                continue
            if not (inspect.isclass(obj) or inspect.isfunction(obj)
                    or hasattr(obj, "py_func")):
                continue
            if not (obj.__doc__ or "").strip():
                missing.append(f"{name}.{symbol}")
            if inspect.isclass(obj):
                missing += [f"{name}.{symbol}.{method}" for method, f in vars(obj).items()
                            if not method.startswith("_") and inspect.isfunction(f)
                            and not (f.__doc__ or "").strip()]
    assert missing == []


def test_the_site_builds_in_strict_mode(tmp_path):
    build = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir",
         str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert build.returncode == 0, build.stderr[-3000:]
    # MkDocs' own warnings (strict mode also fails on them); the notebook's kernel
    # may log one of its own, which is not the site's.
    assert not re.search(r"^WARNING\s+-", build.stderr, re.M), build.stderr[-3000:]
    site = tmp_path / "site"
    assert (site / "reference" / "systems" / "index.html").read_text().count(
        "RhsIntegrator") > 0
    assert "jp-OutputArea" in (site / "tutorial" / "index.html").read_text()


def test_the_entry_points_document_their_arguments_in_google_style():
    """The functions a user calls first, and every LeafSystem's constructor, have
    Google-style sections (Args, Returns) naming every parameter; mkdocstrings
    renders them as tables."""
    from dacph_drake.analysis.metrics import run_metrics
    from dacph_drake.analysis.verify import verify_run
    from dacph_drake.controllers import build_closed_loop
    from dacph_drake.controllers.dac import build_dac_diagram, build_dac_nominal_diagram
    from dacph_drake.controllers.model_based import build_model_based_diagram
    from dacph_drake.loop.closed_loop import (AddLhsSide, RequireOneDiagram,
                                              assemble_closed_loop)
    from dacph_drake.loop.simulate import simulate, simulate_batch
    from dacph_drake.montecarlo.runner import run_sweep
    from dacph_drake.robots import robot_of, robots_of
    from dacph_drake.scenario_files import load_scenario, save_scenario
    from dacph_drake import systems
    leaf_systems = [getattr(importlib.import_module(f"dacph_drake.systems.{module}"),
                            name) for module, name in (
        ("attitude_controller", "AttitudeController"), ("disturbance", "DisturbanceSource"),
        ("inertial_identifier", "InertialIdentifier"), ("learner", "RhsLearner"),
        ("lhs_controller", "LhsController"), ("model_based_inverter", "ModelBasedInverter"),
        ("port_observer", "PortObserver"), ("regression_filter", "RegressionFilter"),
        ("rhs_integrator", "RhsIntegrator"), ("spatial_true_rhs", "SpatialTrueRhs"),
        ("true_rhs", "TrueRhs"))]
    assert systems.__doc__
    for function in (simulate, simulate_batch, build_closed_loop, build_dac_diagram,
                     build_dac_nominal_diagram, build_model_based_diagram,
                     load_scenario, save_scenario, run_sweep, verify_run, run_metrics,
                     assemble_closed_loop, RequireOneDiagram, AddLhsSide, robot_of,
                     robots_of, *leaf_systems):
        doc = inspect.getdoc(function)
        assert "\nArgs:\n" in doc, function.__name__
        arguments = doc.split("\nArgs:\n")[1]
        for name, parameter in inspect.signature(function).parameters.items():
            shown = "*" + name if parameter.kind is parameter.VAR_POSITIONAL else name
            assert re.search(rf"^    {re.escape(shown)}:", arguments, re.M), (
                function.__name__, name)

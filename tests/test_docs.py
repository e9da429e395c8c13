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


# Modules whose every public class and function is in Google style; the rest of the
# package is being converted.
GOOGLE_STYLE_MODULES = ("loop", "loop.simulate", "loop.closed_loop", "loop.run_store",
                        "loop.files", "loop.progress", "loop.simulator", "controllers",
                        "controllers.dac", "controllers.model_based", "montecarlo",
                        "montecarlo.runner", "montecarlo.executors", "montecarlo.store",
                        "montecarlo.trial", "errors", "gain_rule",
                        "network")


def _documents_its_arguments(function) -> list:
    """The parameters of ``function`` (a class: its constructor's) that its
    docstring's Args section (a dataclass's: Attributes) does not name."""
    doc = inspect.getdoc(function) or ""
    try:
        signature = inspect.signature(function)
    except ValueError:              # a built-in's subclass, e.g. ConfigError
        return []
    parameters = [("*" + name if p.kind is p.VAR_POSITIONAL else name)
                  for name, p in signature.parameters.items()
                  if name not in ("self", "cls")]
    if not parameters:
        return []
    section = next((s for s in ("\nArgs:\n", "\nAttributes:\n") if s in doc), None)
    if section is None:
        return parameters
    arguments = doc.split(section)[1]
    return [name for name in parameters
            if not re.search(rf"^    {re.escape(name)}:", arguments, re.M)]


def test_the_converted_api_documents_its_arguments_in_google_style():
    """Google-style sections (Args, Returns, Raises) naming every parameter, which
    mkdocstrings renders as tables: every public class and function of
    GOOGLE_STYLE_MODULES, the other entry points a user calls first, and every
    LeafSystem's constructor."""
    from dacph_drake.analysis.metrics import run_metrics
    from dacph_drake.analysis.verify import verify_run
    from dacph_drake.loop.closed_loop import (AddLhsSide, RequireOneDiagram,
                                              assemble_closed_loop)
    from dacph_drake.montecarlo.runner import run_sweep
    from dacph_drake.robots import robot_of, robots_of
    from dacph_drake.scenario_files import load_scenario, save_scenario
    converted = [load_scenario, save_scenario, run_sweep, verify_run, run_metrics,
                 assemble_closed_loop, RequireOneDiagram, AddLhsSide, robot_of,
                 robots_of]
    for module, name in (
            ("attitude_controller", "AttitudeController"),
            ("disturbance", "DisturbanceSource"),
            ("inertial_identifier", "InertialIdentifier"), ("learner", "RhsLearner"),
            ("lhs_controller", "LhsController"),
            ("model_based_inverter", "ModelBasedInverter"),
            ("port_observer", "PortObserver"), ("regression_filter", "RegressionFilter"),
            ("rhs_integrator", "RhsIntegrator"), ("spatial_true_rhs", "SpatialTrueRhs"),
            ("true_rhs", "TrueRhs")):
        converted.append(getattr(importlib.import_module(
            f"dacph_drake.systems.{module}"), name))
    for name in GOOGLE_STYLE_MODULES:
        module = importlib.import_module(f"dacph_drake.{name}")
        converted += [obj for symbol, obj in vars(module).items()
                      if not symbol.startswith("_")
                      and getattr(obj, "__module__", None) == module.__name__
                      and (inspect.isclass(obj) or inspect.isfunction(obj))]
    missing = {function.__qualname__: _documents_its_arguments(function)
               for function in converted}
    assert {name: names for name, names in missing.items() if names} == {}

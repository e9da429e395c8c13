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
    # Math is rendered (pymdownx.arithmatex + MathJax): the equations page's $...$
    # are all MathJax spans, none left as raw text outside them and code.
    equations = (site / "equations" / "index.html").read_text()
    assert equations.count('class="arithmatex"') > 300
    text = re.sub(r'<(span|div) class="arithmatex">.*?</\1>', "", equations, flags=re.S)
    text = re.sub(r"<(script|code|pre)[^>]*>.*?</\1>", "", text, flags=re.S)
    assert re.findall(r"\$[^$<>]{1,80}\$", text) == []


def _documents_its_arguments(function) -> list:
    """The parameters of ``function`` (a class: its constructor's) that its
    docstring's Args section (a dataclass's: Attributes) does not name."""
    doc = inspect.getdoc(function) or ""
    if getattr(function, "_is_protocol", False):
        return []                   # a Protocol is not instantiated: no constructor
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


def _api_of(module):
    """The public classes, functions (compiled kernels: their Python functions) and
    methods defined in ``module``, by qualified name."""
    for symbol, obj in vars(module).items():
        if symbol.startswith("_") or getattr(obj, "__module__", None) != module.__name__:
            continue
        if hasattr(obj, "py_func"):
            yield f"{module.__name__}.{symbol}", obj.py_func
        elif inspect.isclass(obj) or inspect.isfunction(obj):
            yield f"{module.__name__}.{symbol}", obj
            for method, function in (vars(obj).items() if inspect.isclass(obj) else ()):
                function = getattr(function, "__func__", function)
                if not method.startswith("_") and inspect.isfunction(function):
                    yield f"{module.__name__}.{symbol}.{method}", function


def test_the_api_documents_its_arguments_in_google_style():
    """One docstring style throughout: every public class, function, method and
    compiled kernel of every module has Google-style sections (Args; a dataclass:
    Attributes) naming each of its parameters, which mkdocstrings renders as
    tables (and griffe checks against the signature in the strict build)."""
    missing = {}
    for name in _public_modules():
        for qualified, function in _api_of(importlib.import_module(name)):
            names = _documents_its_arguments(function)
            if names:
                missing[qualified] = names
    assert missing == {}

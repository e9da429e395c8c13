"""The documentation site (mkdocs.yml, docs/): it builds in strict mode (a broken
link, a missing page or a failing cross-reference fails it), the tutorial notebook
executed into it; every public module is in the API reference and every public
class, function and method has a docstring."""
import html
import importlib
import importlib.util
import inspect
import os
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import pytest

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


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The site built once for this module's tests (strict mode, the tutorial
    notebook executed): (its directory, mkdocs' completed process)."""
    out = tmp_path_factory.mktemp("docs") / "site"
    build = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT, capture_output=True, text=True,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    return out, build


def _built(site):
    out, build = site
    if build.returncode != 0:
        pytest.fail(f"the site did not build: {build.stderr[-3000:]}")
    return out


def _pages(site_dir: Path):
    return sorted(site_dir.rglob("index.html"))


def test_the_site_builds_in_strict_mode(site):
    site_dir, build = site
    assert build.returncode == 0, build.stderr[-3000:]
    # MkDocs' own warnings (strict mode also fails on them); the notebook's kernel
    # may log one of its own, which is not the site's.
    assert not re.search(r"^WARNING\s+-", build.stderr, re.M), build.stderr[-3000:]
    assert (site_dir / "reference" / "systems" / "index.html").read_text().count(
        "RhsIntegrator") > 0
    assert "jp-OutputArea" in (site_dir / "tutorial" / "index.html").read_text()
    # Math is rendered (pymdownx.arithmatex + MathJax): the equations page's $...$
    # are all MathJax spans, none left as raw text outside them and code.
    equations = (site_dir / "equations" / "index.html").read_text()
    assert equations.count('class="arithmatex"') > 300
    text = re.sub(r'<(span|div) class="arithmatex">.*?</\1>', "", equations, flags=re.S)
    text = re.sub(r"<(script|code|pre)[^>]*>.*?</\1>", "", text, flags=re.S)
    assert re.findall(r"\$[^$<>]{1,80}\$", text) == []


def test_no_table_cell_shows_an_escaped_bar(site):
    """Python-Markdown's tables keep ``\\|`` literally inside inline code: no
    rendered cell of any page may show those two characters (TeX inside math
    spans, where ``\\|`` is a norm, aside)."""
    shown = []
    for page in _pages(_built(site)):
        for cell in re.findall(r"<t[dh][^>]*>(.*?)</t[dh]>", page.read_text(), re.S):
            cell = re.sub(r'<(span|div) class="arithmatex">.*?</\1>', "", cell,
                          flags=re.S)
            if "\\|" in html.unescape(re.sub(r"<[^>]+>", "", cell)):
                shown.append(f"{page.relative_to(site[0])}: {cell[:80]!r}")
    assert shown == []


def test_no_page_cites_a_file_that_is_not_in_the_repository(site):
    """The project's reading of the paper is listed on the site (equations page,
    Settings explained), not in a file of its own: no page cites SPEC.md."""
    assert not (ROOT / "SPEC.md").exists()
    citing = [str(page.relative_to(site[0])) for page in _pages(_built(site))
              if "SPEC.md" in page.read_text()]
    assert citing == []


def _check_site_module():
    spec = importlib.util.spec_from_file_location(
        "check_site", ROOT / "scripts" / "check_site.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_site_checker_finds_what_it_checks(tmp_path):
    """scripts/check_site.py's checks on a page made to fail each of them, and on
    the same page made right."""
    check = _check_site_module()
    (tmp_path / "there.png").write_bytes(b"")
    page = tmp_path / "index.html"
    page.write_text("<html></html>")
    bad = ('<html><body><div class="md-typeset"><p>raw $x + y$ and '
           '<span class="arithmatex">\\(a\\)</span></p><table><tr><td><code>a\\|b'
           '</code></td></tr></table><img src="missing.png"><a href="#nowhere">x</a>'
           '</div></body></html>')
    report = check.check_dom(bad, page, tmp_path)
    problems = " ".join(report.problems)
    assert "raw TeX" in problems and "\\|" in problems
    assert "missing.png" in problems and "#nowhere" in problems
    assert report.notes == ["MathJax not loaded: arithmatex spans checked"]
    good = ('<html><body><div class="md-typeset" id="top"><p>math '
            '<span class="arithmatex">\\(a\\)</span></p><table><tr><td>a, b</td></tr>'
            '</table><img src="there.png"><a href="#top">x</a></div></body></html>')
    assert check.check_dom(good, page, tmp_path).problems == []
    typeset = good.replace("\\(a\\)", "<mjx-container>a</mjx-container>")
    report = check.check_dom(typeset, page, tmp_path)
    assert report.problems == [] and report.notes == []


# The pages the headless-browser test opens (all of them take minutes:
# scripts/check_site.py checks every page).
BROWSER_PAGES = ["index.html", "getting-started/index.html", "equations/index.html",
                 "how-to/own-robot/index.html", "concepts/closed-loop/index.html",
                 "results/zoo/index.html"]


def test_pages_in_a_headless_browser(site):
    """scripts/check_site.py's checks on pages as Chromium leaves them after their
    scripts ran: math typeset or wrapped for MathJax, no \\| in a table cell, every
    local link and image there."""
    check = _check_site_module()
    if check.chromium() is None:
        pytest.skip("no Chromium (scripts/setup.sh installs Debian's chromium)")
    reports = check.check_site(_built(site), BROWSER_PAGES, shots=None, jobs=2)
    assert [r.line() for r in reports if not r.ok] == []
    assert len(reports) == len(BROWSER_PAGES)


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

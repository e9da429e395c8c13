#!/usr/bin/env python
"""Checks every page of the built documentation site in headless Chromium.

Builds the site (``mkdocs build --strict`` into a temporary directory), or takes one
with ``--site DIR``; then, for every page (each ``index.html``), runs headless
Chromium with a virtual time budget so that the page's scripts (MathJax among them)
run, dumps the DOM they leave and saves a 1280 x 2000 screenshot into ``--shots``
(default: a new temporary directory, printed), and checks in the dumped DOM:

- **math**: no raw TeX (``$...$``, ``\\(...\\)``, ``\\[...\\]``) left outside the
  math containers. When MathJax ran (its CHTML ``mjx-container`` elements are
  there), every arithmatex span must hold one and none may hold a MathJax error;
  when it did not (the page loads MathJax from cdn.jsdelivr.net, which may be
  unreachable), the page is reported with "MathJax not loaded" and the check is
  that pymdownx.arithmatex wrapped all the TeX: none outside its ``<span
  class="arithmatex">`` / ``<div class="arithmatex">``. ``--mathjax FILE`` points
  the pages at a local copy of MathJax 3 (``tex-mml-chtml.js``) instead, in a copy
  of the site, so that the math is typeset offline too;
- **tables**: no table cell shows the two characters ``\\|`` (Python-Markdown's
  tables keep them literally inside inline code);
- **links**: every local ``href`` and ``src`` (links, images, scripts, style
  sheets) resolves to a file in the site, and a ``#fragment`` into a page of the
  site names an element of that page.

Prints one line per page, ``OK`` or its problems, then a summary; exits 1 when a page
has a problem (or Chromium failed on it), 0 otherwise.

    .venv/bin/python scripts/check_site.py                       # build, check all
    .venv/bin/python scripts/check_site.py --site /tmp/site --shots /tmp/shots
    .venv/bin/python scripts/check_site.py --site /tmp/site --page index.html \\
        --page equations/index.html --mathjax PATH/TO/es5/tex-mml-chtml.js
"""
import argparse
import html
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path
from typing import Dict, Iterable, List, Optional, Sequence, Set, Union
from urllib.parse import unquote, urljoin, urlsplit

ROOT = Path(__file__).resolve().parents[1]
MATHJAX_CDN = re.compile(r'src="https://cdn\.jsdelivr\.net/npm/mathjax@3/[^"]*"')
VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta",
        "param", "source", "track", "wbr"}
NO_MATH_TEXT = {"script", "style", "code", "pre", "textarea", "kbd", "samp"}
BLOCKS = {"p", "li", "td", "th", "div", "h1", "h2", "h3", "h4", "h5", "h6",
          "dd", "dt", "figcaption", "blockquote", "summary", "caption"}
RAW_TEX = [re.compile(r"(?<![\\$])\$(?!\s)[^$\n]{1,200}?(?<![\s\\])\$(?!\d)"),
           re.compile(r"\\\(.{1,300}?\\\)", re.S), re.compile(r"\\\[.{1,600}?\\\]", re.S),
           re.compile(r"\$\$.{1,600}?\$\$", re.S)]
LINK_ATTRIBUTES = {"a": "href", "link": "href", "img": "src", "script": "src",
                   "source": "src", "iframe": "src", "embed": "src", "video": "src",
                   "audio": "src"}


def chromium() -> Optional[str]:
    """The Chromium executable (``chromium``, ``chromium-browser`` or
    ``google-chrome`` on the PATH, or /usr/bin/chromium), or None."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    return "/usr/bin/chromium" if os.access("/usr/bin/chromium", os.X_OK) else None


def build_site(out: Path) -> Path:
    """Builds the site into ``out`` with ``mkdocs build --strict`` (the tutorial
    notebook not executed unless DACPH_DOCS_EXECUTE_NOTEBOOK says so); raises
    RuntimeError with mkdocs' output when the build fails."""
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    env.setdefault("DACPH_DOCS_EXECUTE_NOTEBOOK", "false")
    build = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict",
                            "--site-dir", str(out)], cwd=ROOT, env=env,
                           capture_output=True, text=True)
    if build.returncode != 0:
        raise RuntimeError(f"mkdocs build failed:\n{build.stderr[-4000:]}")
    return out


def run_chromium(page: Union[Path, str], action: str, *, window: str = "1280,2000",
                 virtual_time_ms: int = 10000, wall_limit: float = 60.0,
                 attempts: int = 3, executable: Optional[str] = None,
                 flags: Sequence[str] = ()) -> str:
    """Runs ``chromium --headless=new ... FLAGS ACTION file://PAGE`` (ACTION
    ``--dump-dom`` or ``--screenshot=PATH``; PAGE a path or a URI) and returns its
    stdout. Each attempt
    gets a fresh profile and a wall-clock limit (Chromium's virtual time budget
    hangs now and then); a hung or failed attempt is retried. Raises RuntimeError
    when every attempt failed."""
    failures = []
    for _ in range(attempts):
        with tempfile.TemporaryDirectory() as profile:
            command = [executable or chromium() or "chromium", "--headless=new",
                       "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                       "--allow-file-access-from-files", f"--user-data-dir={profile}",
                       f"--window-size={window}",
                       f"--virtual-time-budget={virtual_time_ms}", *flags, action,
                       page if isinstance(page, str) else page.resolve().as_uri()]
            process = subprocess.Popen(command, stdout=subprocess.PIPE,
                                       stderr=subprocess.PIPE, text=True,
                                       start_new_session=True)
            try:
                stdout, stderr = process.communicate(timeout=wall_limit)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.communicate()
                failures.append(f"no exit within {wall_limit:g} s")
                continue
            if process.returncode == 0:
                return stdout
            failures.append(f"exit {process.returncode}: {stderr.strip()[-300:]}")
    raise RuntimeError(f"Chromium failed {attempts} times: {'; '.join(failures)}")


class _Page(HTMLParser):
    """What the checks need of a (well-formed, serialized) DOM: text runs outside
    math and code, table cells' text outside math, math containers, local links
    and element ids."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack: List[tuple] = []        # (tag, is_math, is_mathjax, no_text)
        self.runs: List[str] = []           # text outside math and code, by block
        self.run: List[str] = []
        self.cells: List[str] = []
        self.cell: Optional[List[str]] = None
        self.arithmatex = 0                 # arithmatex containers
        self.arithmatex_typeset = 0         # ... holding an mjx-container
        self.mjx_containers = 0
        self.mjx_errors = 0
        self.links: List[str] = []
        self.ids: Set[str] = set()
        self._arithmatex_open: List[bool] = []  # per open arithmatex: typeset?

    def _inside(self, index: int) -> bool:
        return any(entry[index] for entry in self.stack)

    def _flush(self):
        if self.run:
            self.runs.append("".join(self.run))
            self.run = []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        classes = (attrs.get("class") or "").split()
        if attrs.get("id"):
            self.ids.add(attrs["id"])
        if attrs.get("name") and tag == "a":
            self.ids.add(attrs["name"])
        attribute = LINK_ATTRIBUTES.get(tag)
        if attribute and attrs.get(attribute):
            self.links.append(attrs[attribute])
        if tag in BLOCKS:
            self._flush()
        if tag in ("td", "th"):
            self.cell = []
        if tag.startswith("mjx-merror") or "data-mjx-error" in attrs:
            self.mjx_errors += 1
        if tag == "mjx-container":
            self.mjx_containers += 1
            if self._arithmatex_open:
                self._arithmatex_open[-1] = True
        if tag in VOID:
            return
        is_math = tag in ("span", "div") and "arithmatex" in classes
        if is_math:
            self.arithmatex += 1
            self._arithmatex_open.append(False)
        self.stack.append((tag, is_math, tag == "mjx-container", tag in NO_MATH_TEXT))

    def handle_startendtag(self, tag, attrs):
        self.handle_starttag(tag, attrs)
        if tag not in VOID:
            self.handle_endtag(tag)

    def handle_endtag(self, tag):
        if tag in VOID:
            return
        while self.stack:
            open_tag, is_math, _, _ = self.stack.pop()
            if is_math:
                self.arithmatex_typeset += self._arithmatex_open.pop()
            if open_tag == tag:
                break
        if tag in BLOCKS:
            self._flush()
        if tag in ("td", "th") and self.cell is not None:
            self.cells.append("".join(self.cell))
            self.cell = None

    def handle_data(self, data):
        in_math = self._inside(1) or self._inside(2)
        if self.cell is not None and not in_math:
            self.cell.append(data)
        if not in_math and not self._inside(3):
            self.run.append(data)

    def close(self):
        super().close()
        self._flush()


@dataclass
class PageReport:
    """One page's result: its path in the site, its problems (empty: OK), notes
    (e.g. MathJax not loaded) and its screenshot, if one was taken."""
    page: str
    problems: List[str] = field(default_factory=list)
    notes: List[str] = field(default_factory=list)
    screenshot: Optional[Path] = None

    @property
    def ok(self) -> bool:
        """No problem found."""
        return not self.problems

    def line(self) -> str:
        """The page's line of the report."""
        notes = f" ({'; '.join(self.notes)})" if self.notes else ""
        if self.ok:
            return f"OK    {self.page}{notes}"
        return f"FAIL  {self.page}{notes}: {'; '.join(self.problems)}"


def _ids_of(path: Path, cache: Dict[Path, Set[str]]) -> Set[str]:
    if path not in cache:
        parser = _Page()
        parser.feed(path.read_text(errors="replace"))
        parser.close()
        cache[path] = parser.ids
    return cache[path]


def check_dom(dom: str, page: Path, site: Path,
              id_cache: Optional[Dict[Path, Set[str]]] = None) -> PageReport:
    """The checks of one page's DOM (as Chromium dumped it, or as built).

    Args:
        dom: The page's HTML.
        page: The page's file in the site (links resolve against it).
        site: The site's root directory.
        id_cache: Element ids of the site's pages by file, filled as needed."""
    id_cache = {} if id_cache is None else id_cache
    report = PageReport(str(page.relative_to(site)))
    parser = _Page()
    parser.feed(dom)
    parser.close()
    if parser.mjx_containers:
        untypeset = parser.arithmatex - parser.arithmatex_typeset
        if untypeset > 0:
            report.problems.append(f"{untypeset} of {parser.arithmatex} math spans "
                                   "not typeset by MathJax")
        if parser.mjx_errors:
            report.problems.append(f"{parser.mjx_errors} MathJax errors")
    elif parser.arithmatex:
        report.notes.append("MathJax not loaded: arithmatex spans checked")
    raw = [match.group(0) for text in parser.runs for pattern in RAW_TEX
           for match in pattern.finditer(text)]
    if raw:
        shown = ", ".join(repr(r[:40]) for r in raw[:3])
        report.problems.append(f"raw TeX outside math containers ({len(raw)}): {shown}")
    cells = [c.strip() for c in parser.cells if "\\|" in c]
    if cells:
        report.problems.append(f"table cells showing '\\|' ({len(cells)}): "
                               + ", ".join(repr(c[:50]) for c in cells[:3]))
    broken = []
    base = page.resolve().as_uri()
    root = site.resolve()
    for link in dict.fromkeys(parser.links):
        link = html.unescape(link).strip()
        parts = urlsplit(link)
        if parts.scheme and parts.scheme != "file" or link.startswith("//") or (
                not parts.path and not parts.fragment):
            continue
        target_parts = urlsplit(urljoin(base, link))
        target = Path(unquote(target_parts.path))
        if target.is_dir() or target_parts.path.endswith("/"):
            target = target / "index.html"
        if root not in target.parents and target != root:
            broken.append(f"{link} (outside the site)")
        elif not target.is_file():
            broken.append(link)
        elif parts.fragment and target.suffix == ".html" and unquote(
                parts.fragment) not in (parser.ids if target == page.resolve()
                                        else _ids_of(target, id_cache)):
            broken.append(f"{link} (no such anchor)")
    if broken:
        report.problems.append(f"broken local links ({len(broken)}): "
                               + ", ".join(broken[:5]))
    return report


def pages_of(site: Path) -> List[Path]:
    """Every page of the site: its index.html files, the home page first."""
    return sorted(site.rglob("index.html"), key=lambda p: (len(p.parts), str(p)))


def _with_local_mathjax(site: Path, mathjax: Path, into: Path) -> Path:
    """A copy of ``site`` whose pages load ``mathjax`` (copied into it with the
    folder it is in, for its fonts and extensions) instead of the CDN's."""
    shutil.copytree(site, into)
    shutil.copytree(mathjax.resolve().parent, into / "_mathjax")
    script = into / "_mathjax" / mathjax.name
    for page in into.rglob("*.html"):
        text = page.read_text(errors="replace")
        if MATHJAX_CDN.search(text):
            source = Path(os.path.relpath(script, page.parent)).as_posix()
            page.write_text(MATHJAX_CDN.sub(f'src="{source}"', text))
    return into


def check_site(site: Path, pages: Optional[Sequence[str]] = None,
               shots: Optional[Path] = None, jobs: int = 2,
               mathjax: Optional[Path] = None,
               executable: Optional[str] = None) -> List[PageReport]:
    """Checks pages of a built site in headless Chromium (see the module's
    docstring) and returns one report per page.

    Args:
        site: The built site's directory.
        pages: Pages to check, relative to ``site`` (default: every index.html).
        shots: Where to save a screenshot per page (None: none taken).
        jobs: Chromium runs at once.
        mathjax: A local MathJax 3 ``tex-mml-chtml.js`` the pages load instead of
            the CDN's (checked in a temporary copy of the site).
        executable: The Chromium executable (default: found on the PATH)."""
    site = Path(site).resolve()
    with tempfile.TemporaryDirectory() as scratch:
        if mathjax is not None:
            site = _with_local_mathjax(site, Path(mathjax), Path(scratch) / "site")
        files = ([site / p for p in pages] if pages is not None else pages_of(site))
        if shots is not None:
            Path(shots).mkdir(parents=True, exist_ok=True)
        id_cache: Dict[Path, Set[str]] = {}

        def one(page: Path) -> PageReport:
            name = str(page.relative_to(site))
            if not page.is_file():
                return PageReport(name, [f"no such page in {site}"])
            try:
                dom = run_chromium(page, "--dump-dom", executable=executable)
            except RuntimeError as error:
                return PageReport(name, [str(error)])
            report = check_dom(dom, page, site, id_cache)
            if shots is not None:
                shot = Path(shots).resolve() / (
                    name.replace("/index.html", "").replace("/", "_")
                    .replace("index.html", "index") + ".png")
                try:
                    run_chromium(page, f"--screenshot={shot}", executable=executable)
                    report.screenshot = shot
                except RuntimeError as error:
                    report.problems.append(f"screenshot: {error}")
            return report

        with ThreadPoolExecutor(max(1, jobs)) as pool:
            return list(pool.map(one, files))


def main(argv: Optional[Iterable[str]] = None) -> int:
    """The command line (see the module's docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--site", type=Path,
                        help="a built site (default: build one into a temporary "
                             "directory with mkdocs build --strict)")
    parser.add_argument("--shots", type=Path,
                        help="directory for the screenshots (default: a new "
                             "temporary directory)")
    parser.add_argument("--page", action="append", dest="pages",
                        help="a page to check, relative to the site (repeatable; "
                             "default: every index.html)")
    parser.add_argument("--jobs", type=int, default=2, help="Chromium runs at once")
    parser.add_argument("--mathjax", type=Path,
                        help="a local MathJax 3 tex-mml-chtml.js to load instead of "
                             "the CDN's")
    args = parser.parse_args(argv)
    executable = chromium()
    if executable is None:
        print("check_site: no Chromium found (scripts/setup.sh installs Debian's "
              "chromium)", file=sys.stderr)
        return 2
    shots = args.shots or Path(tempfile.mkdtemp(prefix="dacph-site-shots-"))
    if ROOT in shots.resolve().parents or shots.resolve() == ROOT:
        print(f"check_site: --shots {shots} is inside the repository; allowed: a "
              "directory outside it", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="dacph-site-") as scratch:
        site = args.site
        if site is None:
            print("building the site ...", flush=True)
            try:
                site = build_site(Path(scratch) / "site")
            except RuntimeError as error:
                print(error, file=sys.stderr)
                return 1
        reports = check_site(site, args.pages, shots, args.jobs, args.mathjax,
                             executable)
    for report in reports:
        print(report.line())
    ok = sum(r.ok for r in reports)
    print(f"{len(reports)} pages, {ok} OK, {len(reports) - ok} with problems; "
          f"screenshots in {shots}")
    return 0 if ok == len(reports) else 1


if __name__ == "__main__":
    sys.exit(main())

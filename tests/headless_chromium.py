"""Headless Chromium for the animation tests: a page opened offline (the network goes
to an unreachable proxy), WebGL in software, a fixed virtual time budget.

Chromium's ``--virtual-time-budget`` hangs now and then before it writes anything
(seen here about once in fifteen runs of the same page, and reported upstream, e.g.
vgalin/html2image#97, "hangs 1 out of 10 cases"). One CI run failed on it: the
screenshot of a page whose DOM dump had just succeeded never came. So each
browser run gets a wall-clock limit, a fresh profile, and its process group is
killed when the limit passes; a hung run is started again, up to ``attempts``
times (scripts/check_site.run_chromium, which the site check shares). What the
tests assert about the page is unchanged: a run that finishes is used as it is.
"""
import importlib.util
from pathlib import Path

import pytest

_spec = importlib.util.spec_from_file_location(
    "check_site", Path(__file__).resolve().parents[1] / "scripts" / "check_site.py")
_site = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_site)

OFFLINE_WEBGL = ("--enable-unsafe-swiftshader", "--use-angle=swiftshader",
                 "--proxy-server=127.0.0.1:9")


def chromium() -> str:
    executable = _site.chromium()
    if executable is None:
        pytest.fail("no Chromium: scripts/setup.sh installs Debian's chromium package")
    return executable


def run_chromium(page_uri: str, action: str, *, virtual_time_ms: int,
                 wall_limit: float = 60.0, attempts: int = 3) -> str:
    """Runs ``chromium --headless=new <action> page_uri`` (action: "--dump-dom" or
    "--screenshot=PATH") offline with WebGL in software, in an 800 x 800 window, and
    returns its stdout; fails the test with Chromium's last stderr if every attempt
    passed ``wall_limit`` seconds or exited non-zero."""
    try:
        return _site.run_chromium(page_uri, action, window="800,800",
                                  virtual_time_ms=virtual_time_ms,
                                  wall_limit=wall_limit, attempts=attempts,
                                  executable=chromium(), flags=OFFLINE_WEBGL)
    except RuntimeError as error:
        pytest.fail(f"headless Chromium failed on {page_uri}: {error}")

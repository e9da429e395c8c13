import numpy as np
import pytest

from dacph_drake.scenario.planar_arm import RobotParams, unequal_three_link_arm


def three_link_robot() -> RobotParams:
    """A 3-link arm with unequal, off-centre links (nothing tied to two links)."""
    return unequal_three_link_arm()


@pytest.fixture(params=["paper_2link", "3link"])
def robot(request) -> RobotParams:
    return RobotParams() if request.param == "paper_2link" else three_link_robot()


@pytest.fixture
def rng():
    return np.random.default_rng(1234)


def pytest_addoption(parser):
    parser.addoption("--long", action="store_true",
                     help="also run the long tests (full paper scenario, big sweeps)")


def pytest_collection_modifyitems(config, items):
    if config.getoption("--long"):
        return
    skip = pytest.mark.skip(reason="long run: use --long")
    for item in items:
        if "long" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def quick_reproduction(tmp_path_factory):
    """`dacph reproduce --quick --animate` run once per session, end to end through
    the CLI: (exit status, output directory)."""
    from dacph_drake.app.cli import main
    out = tmp_path_factory.mktemp("reproduce_quick")
    status = main(["reproduce", "--quick", "--animate", "--out", str(out)])
    return status, out

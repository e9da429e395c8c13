"""Robot description: defaults, YAML round trip, and one clear error per bad field."""
import dataclasses

import pytest

from dacph_drake.scenario.errors import ConfigError
from dacph_drake.scenario.planar_arm import (BaseParams, LinkParams, RobotParams,
                                             load_robot, save_robot)


def test_paper_robot_is_the_default_and_valid():
    robot = RobotParams()
    robot.Validate()
    assert robot.num_links == 2
    assert (robot.base.mass, robot.base.size / 2, robot.base.inertia) == (2.0, 0.1225, 0.02)
    for link in robot.links:
        assert (link.mass, link.length, link.inertia) == (1.0, 0.3464, 0.01)
        # SPEC section 1: uniform rods, I = m l^2 / 12.
        assert link.inertia == pytest.approx(link.mass * link.length**2 / 12, rel=1e-3)


def test_yaml_round_trip(tmp_path, robot):
    path = tmp_path / "robot.yaml"
    save_robot(robot, path)
    assert load_robot(path) == robot


def test_yaml_unknown_key_and_wrong_type(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_text("base: {mass: 2.0, colour: red}\n")
    with pytest.raises(ConfigError, match=r"robot.yaml.*colour"):
        load_robot(path)
    path.write_text("base: {mass: heavy}\n")
    with pytest.raises(ConfigError, match=r"robot.yaml.*heavy"):
        load_robot(path)


def _with_link(**changes) -> RobotParams:
    return RobotParams(links=[LinkParams(), dataclasses.replace(LinkParams(), **changes)])


@pytest.mark.parametrize("robot, message", [
    (RobotParams(base=BaseParams(mass=0.0)), r"robot.base.mass = 0.0 .*> 0 kg"),
    (RobotParams(base=BaseParams(mass=-1.0)), r"robot.base.mass = -1.0 .*> 0 kg"),
    (RobotParams(base=BaseParams(size=0.0)), r"robot.base.size = 0.0 .*> 0 m"),
    (RobotParams(base=BaseParams(inertia=0.1)), r"robot.base.inertia = 0.1 .*m a\^2 / 2"),
    (RobotParams(base=BaseParams(inertia=0.0)), r"robot.base.inertia = 0.0 "),
    (RobotParams(base=BaseParams(shoulder_offset=0.05)),
     r"robot.base.shoulder_offset = 0.05 .*on or outside the base"),
    (RobotParams(links=[]), r"robot.links is empty; allowed: at least 1 link"),
    (_with_link(mass=0.0), r"robot.links\[1\].mass = 0.0 .*> 0 kg"),
    (_with_link(length=-0.3), r"robot.links\[1\].length = -0.3 .*> 0 m"),
    (_with_link(width=0.0), r"robot.links\[1\].width = 0.0 .*> 0 m"),
    (_with_link(com=0.5), r"robot.links\[1\].com = 0.5 .*0 <= com <= length"),
    (_with_link(inertia=0.05), r"robot.links\[1\].inertia = 0.05 .*rod bound"),
    (_with_link(inertia=-0.01), r"robot.links\[1\].inertia = -0.01 .*rod bound"),
    (_with_link(mass=float("nan")), r"robot.links\[1\].mass = nan"),
])
def test_each_invalid_field_is_named(robot, message):
    with pytest.raises(ConfigError, match=message):
        robot.Validate()


def test_rod_bound_is_tight():
    # At the bound the lamina tensor still satisfies the triangle inequality and
    # Drake accepts it; just above it the description is refused.
    from dacph_drake.dynamics.plant import MakeArmPlant
    from dacph_drake.scenario.planar_arm import link_inertia_bound
    link = LinkParams(mass=1.0, length=0.3, com=0.1, width=0.02)
    link.inertia = link_inertia_bound(link)
    MakeArmPlant(RobotParams(links=[link]))
    link.inertia *= 1.0001
    with pytest.raises(ConfigError, match="inertia"):
        RobotParams(links=[link]).Validate()

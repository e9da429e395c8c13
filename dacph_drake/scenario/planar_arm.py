"""Description of a planar free-floating arm: a base on a free planar joint and n revolute
links in the x-y plane, zero gravity, each link's frame at its proximal joint with x along
the link; the defaults are the paper's robot (docs/equations.md)."""
from dataclasses import dataclass, field
from typing import List

from pydrake.common.yaml import yaml_dump_typed

from dacph_drake.scenario.errors import ConfigError, require_in_range, require_positive
from dacph_drake.scenario.yaml_files import load_yaml_dataclass


@dataclass
class BaseParams:
    """The spacecraft base: a uniform-thickness square plate of side ``size``.

    Attributes:
        mass: The base's mass m [kg], > 0.
        inertia: Its central inertia I about the z axis [kg m^2], 0 < I <= m a^2 / 2.
        size: The side a of the square [m], > 0.
        shoulder_offset: Base centre to shoulder along base x [m], [size / 2, 100 size]."""
    mass: float = 2.0               # [kg]
    inertia: float = 0.02           # about its centre of mass, z axis [kg m^2]
    size: float = 0.245             # side of the square [m]
    shoulder_offset: float = 0.1225  # base centre to shoulder joint, base x axis [m]


@dataclass
class LinkParams:
    """One link: a slender lamina of ``length`` x ``width`` in the plane.

    Attributes:
        mass: The link's mass m [kg], > 0.
        length: Proximal joint to the next joint (or the end effector) l [m], > 0.
        inertia: Its inertia I about its centre of mass, z axis [kg m^2],
            0 < I <= m (c (l - c) + w^2 / 4) (link_inertia_bound).
        com: Proximal joint to the centre of mass c, along x [m], in [0, length].
        width: Its extent w across the link (geometry, inertia bound) [m], > 0."""
    mass: float = 1.0               # [kg]
    length: float = 0.3464          # joint to next joint (or end effector) [m]
    inertia: float = 0.01           # about its centre of mass, z axis [kg m^2]
    com: float = 0.1732             # proximal joint to centre of mass, along x [m]
    width: float = 0.04             # extent across the link (geometry, inertia bound) [m]


def _paper_links() -> List[LinkParams]:
    return [LinkParams(), LinkParams()]


@dataclass
class RobotParams:
    """A planar free-floating arm with ``len(links)`` revolute joints.

    Attributes:
        base: The base (BaseParams).
        links: The links from the shoulder out (LinkParams), at least one."""
    base: BaseParams = field(default_factory=BaseParams)
    links: List[LinkParams] = field(default_factory=_paper_links)

    @property
    def num_links(self) -> int:
        return len(self.links)

    def Validate(self, name: str = "robot") -> None:
        """Checks every field's range. The inertia bounds keep the mass in the body's
        outline (link_inertia_bound; base: I <= m a^2 / 2): the lamina's Ixx + Iyy >= Izz.

        Args:
            name: The robot's setting path, for the messages (e.g. robot.truth).

        Raises:
            ConfigError: Naming the first invalid field and its allowed range."""
        b = self.base
        require_positive(f"{name}.base.mass", b.mass, "kg")
        require_positive(f"{name}.base.size", b.size, "m")
        require_in_range(f"{name}.base.inertia", b.inertia, 1e-12,
                         b.mass * b.size**2 / 2, "kg m^2 (0 < I <= m a^2 / 2)")
        require_in_range(f"{name}.base.shoulder_offset", b.shoulder_offset,
                         b.size / 2, 100.0 * b.size,
                         "m (the shoulder sits on or outside the base's side)")
        if len(self.links) == 0:
            raise ConfigError(
                f"{name}.links is empty; allowed: at least 1 link")
        for k, link in enumerate(self.links):
            where = f"{name}.links[{k}]"
            require_positive(f"{where}.mass", link.mass, "kg")
            require_positive(f"{where}.length", link.length, "m")
            require_positive(f"{where}.width", link.width, "m")
            require_in_range(f"{where}.com", link.com, 0.0, link.length,
                             "m (0 <= com <= length)")
            require_in_range(
                f"{where}.inertia", link.inertia, 1e-12, link_inertia_bound(link),
                "kg m^2 (rod bound 0 < I <= m (c (l - c) + w^2 / 4))")


def unequal_three_link_arm() -> RobotParams:
    """A 3-link arm of unequal, off-centre links: the tests' second planar arm."""
    return RobotParams(links=[
        LinkParams(mass=1.2, length=0.30, inertia=0.008, com=0.12),
        LinkParams(mass=0.8, length=0.25, inertia=0.004, com=0.14),
        LinkParams(mass=0.5, length=0.20, inertia=0.002, com=0.09)])


def link_inertia_bound(link: LinkParams) -> float:
    """The rod bound m (c (l - c) + w^2 / 4) [kg m^2]: the largest central inertia of mass
    confined to the link's l x w rectangle with its centre of mass at ``com``.

    Args:
        link: The link."""
    return link.mass * (link.com * (link.length - link.com) + link.width**2 / 4)


def load_robot(path: str) -> RobotParams:
    """Loads and validates a RobotParams YAML file.

    Args:
        path: The YAML file.

    Raises:
        ConfigError: An unreadable file, one not fitting RobotParams, or out of range."""
    robot = load_yaml_dataclass(path, RobotParams)
    robot.Validate()
    return robot


def save_robot(robot: RobotParams, path: str) -> None:
    """Writes a robot as typed YAML (load_robot reads it back).

    Args:
        robot: The robot.
        path: The file to write."""
    with open(path, "w") as f:
        f.write(yaml_dump_typed(robot))

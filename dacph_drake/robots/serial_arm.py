"""Serial arms of cylinders as URDF text: test arms of any shape (the zoo's heavy
joint damping, tiny wrist, long chain, heavy tool and light base;
scripts/zoo.py), written without a CAD model.

Link k is a solid cylinder of its mass, length L and radius max(0.1 L, 1 cm)
along its frame's z axis (its centre of mass at L / 2), hinged to the previous
link's tip about the k-th of ``axes`` (cycled), with limits +-2.9 rad, an effort
limit of 1000 N m and the given damping; a massless frame "tool" sits at the last
link's tip, and a tool mass is added to the last link."""
from dataclasses import dataclass
from typing import Sequence

AXES = ("0 0 1", "0 1 0", "1 0 0")


@dataclass
class SerialLink:
    """One link of a serial_arm_urdf arm.

    Attributes:
        mass: [kg], > 0.
        length: [m], > 0.
        damping: Its joint's damping [N m s/rad], >= 0."""
    mass: float
    length: float
    damping: float = 0.0


def serial_arm_urdf(name: str, links: Sequence[SerialLink], tool_mass: float = 0.0,
                    axes: Sequence[str] = AXES) -> str:
    """The URDF text of a serial arm (module docstring).

    Args:
        name: The robot's name.
        links: Its links, from the root outwards.
        tool_mass: A mass added to the last link [kg].
        axes: The joints' axes as URDF "x y z" strings, cycled."""
    parts = [f'<robot name="{name}"><link name="root"><inertial><mass value="1.0"/>'
             '<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>'
             '</inertial><collision><geometry><cylinder radius="0.05" length="0.05"/>'
             '</geometry></collision></link>']
    parent, offset = "root", 0.05
    for k, link in enumerate(links):
        mass = link.mass + (tool_mass if k == len(links) - 1 else 0.0)
        radius = max(0.1 * link.length, 0.01)
        lateral = mass * (3 * radius**2 + link.length**2) / 12
        axial = mass * radius**2 / 2
        parts.append(
            f'<link name="link{k + 1}"><inertial><origin xyz="0 0 {link.length / 2:g}"/>'
            f'<mass value="{mass:g}"/><inertia ixx="{lateral:g}" iyy="{lateral:g}" '
            f'izz="{axial:g}" ixy="0" ixz="0" iyz="0"/></inertial><collision>'
            f'<origin xyz="0 0 {link.length / 2:g}"/><geometry><cylinder '
            f'radius="{radius:g}" length="{link.length:g}"/></geometry></collision>'
            f'</link><joint name="joint{k + 1}" type="revolute"><parent link="{parent}"/>'
            f'<child link="link{k + 1}"/><origin xyz="0 0 {offset:g}"/>'
            f'<axis xyz="{axes[k % len(axes)]}"/><limit lower="-2.9" upper="2.9" '
            f'effort="1000" velocity="5"/><dynamics damping="{link.damping:g}"/>'
            '</joint>')
        parent, offset = f"link{k + 1}", link.length
    parts.append(f'<link name="tool"/><joint name="tool_weld" type="fixed"><parent '
                 f'link="{parent}"/><child link="tool"/><origin xyz="0 0 {offset:g}"/>'
                 '</joint></robot>')
    return "".join(parts)

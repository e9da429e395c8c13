"""Serial arms of cylinders as URDF text: test arms of any shape (scripts/zoo.py) without
a CAD model. Link k is a solid cylinder (length L, radius max(0.1 L, 1 cm)) along its
z axis, hinged to the previous tip about the k-th of ``axes`` (cycled), limits +-2.9
rad, effort limit 1000 N m; a frame "tool" at the last tip, the tool mass in that link."""
from dataclasses import dataclass
from typing import Dict, Sequence

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


def serial_arm_mjcf(name: str, links: Sequence[SerialLink], tool_mass: float = 0.0,
                    axes: Sequence[str] = AXES, armature: Sequence[float] = (),
                    frictionloss: float = 0.0, from_geoms: Sequence[bool] = ()
                    ) -> Dict[str, str]:
    """The serial_arm_urdf arm as MJCF, written as MuJoCo models are: {file name: text} of
    NAME.xml including NAME_arm.xml; limits and ``frictionloss`` from a <default> class
    passed down by ``childclass``; ``armature`` on each joint; inertia from the cylinder
    geom where ``from_geoms``; a massless body "tool" at the tip.

    Args:
        name: The robot's name (its files' stem).
        links: Its links, from the root outwards.
        tool_mass: A mass added to the last link [kg].
        axes: The joints' axes as "x y z" strings, cycled.
        armature: Each joint's armature [kg m^2] (none: 0).
        frictionloss: Every joint's frictionloss [N m] (the class's).
        from_geoms: Per link, whether its inertia comes from its geom (none: no)."""
    bodies, closing = [], []
    offset = 0.05
    for k, link in enumerate(links):
        mass = link.mass + (tool_mass if k == len(links) - 1 else 0.0)
        radius = max(0.1 * link.length, 0.01)
        lateral = mass * (3 * radius**2 + link.length**2) / 12
        axial = mass * radius**2 / 2
        geometric = k < len(from_geoms) and from_geoms[k]
        inertial = ("" if geometric else
                    f'<inertial pos="0 0 {link.length / 2:g}" mass="{mass:g}" '
                    f'diaginertia="{lateral:g} {lateral:g} {axial:g}"/>')
        geom_mass = f' mass="{mass:g}"' if geometric else ""
        bodies.append(
            f'<body name="link{k + 1}" pos="0 0 {offset:g}"'
            + (' childclass="arm"' if k == 0 else "") + ">"
            f'<joint name="joint{k + 1}" axis="{axes[k % len(axes)]}" '
            f'damping="{link.damping:g}" armature="{armature[k] if k < len(armature) else 0.0:g}"/>'
            f'{inertial}<geom name="link{k + 1}_geom" type="cylinder" '
            f'fromto="0 0 0 0 0 {link.length:g}" size="{radius:g}"{geom_mass}/>')
        closing.append("</body>")
        offset = link.length
    bodies.append(f'<body name="tool" pos="0 0 {offset:g}"/>')
    arm = "<mujoco>" + "".join(bodies) + "".join(closing) + "</mujoco>\n"
    main = (f'<mujoco model="{name}"><compiler angle="radian"/><default>'
            f'<default class="arm"><joint limited="true" range="-2.9 2.9" '
            f'frictionloss="{frictionloss:g}"/></default></default><worldbody>'
            '<body name="root"><inertial pos="0 0 0" mass="1" '
            'diaginertia="0.01 0.01 0.01"/><geom name="root_geom" type="cylinder" '
            f'size="0.05 0.025"/><include file="{name}_arm.xml"/></body></worldbody>'
            "</mujoco>\n")
    return {f"{name}.xml": main, f"{name}_arm.xml": arm}

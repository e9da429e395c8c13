"""Generates the spatial example robots' URDF (a one-off; the files are committed)."""
from pathlib import Path

import numpy as np

MODELS = Path(__file__).resolve().parents[1] / "dacph_drake" / "models"

def cyl_inertia(m, r, L):     # cylinder along its local z
    return m * (3 * r * r + L * L) / 12, m * (3 * r * r + L * L) / 12, m * r * r / 2

def link_xml(name, m, I, xyz, shape, material):
    """A link: mass m, principal inertia I = (ixx, iyy, izz) at xyz; ``shape`` (origin
    and geometry) is both its visual and its collision geometry (the controller's
    clearance potential queries it; the ground truth drops it)."""
    return f"""  <link name="{name}">
    <inertial>
      <origin xyz="{xyz}" rpy="0 0 0"/>
      <mass value="{m:g}"/>
      <inertia ixx="{I[0]:.6g}" ixy="0" ixz="0" iyy="{I[1]:.6g}" iyz="0" izz="{I[2]:.6g}"/>
    </inertial>
    <visual>
{shape}
      <material name="{material}"/>
    </visual>
    <collision>
{shape}
    </collision>
  </link>
"""


def cylinder_link_xml(name, m, r, L, axis_along, color):
    """A cylinder of length L along ``axis_along`` ('x' or 'z'), from the joint."""
    ixx_c, iyy_c, izz_c = cyl_inertia(m, r, L)
    if axis_along == "z":
        xyz, rpy, I = f"0 0 {L/2:g}", "0 0 0", (ixx_c, iyy_c, izz_c)
    else:  # along x: rotate the cylinder's z onto x
        xyz, rpy, I = f"{L/2:g} 0 0", f"0 {np.pi/2:.6f} 0", (izz_c, ixx_c, iyy_c)
    return link_xml(name, m, I, xyz, f"""      <origin xyz="{xyz}" rpy="{rpy}"/>
      <geometry><cylinder radius="{r:g}" length="{L:g}"/></geometry>""", color)

def joint_xml(k, parent, child, xyz, axis):
    return f"""  <joint name="joint{k}" type="continuous">
    <parent link="{parent}"/>
    <child link="{child}"/>
    <origin xyz="{xyz}" rpy="0 0 0"/>
    <axis xyz="{axis}"/>
  </joint>
"""

def robot(name, base_size, base_mass, links, comment):
    a = base_size
    Ib = base_mass * (2 * a * a) / 12
    out = [f'<?xml version="1.0"?>\n<!-- {comment} -->\n<robot name="{name}">\n',
           '  <material name="base"><color rgba="0.75 0.75 0.8 1"/></material>\n',
           '  <material name="orange"><color rgba="0.85 0.45 0.1 1"/></material>\n',
           '  <material name="blue"><color rgba="0.2 0.45 0.8 1"/></material>\n',
           link_xml("base", base_mass, (Ib, Ib, Ib), "0 0 0",
                    f"""      <geometry><box size="{a:g} {a:g} {a:g}"/></geometry>""",
                    "base")]
    parent, offset = "base", f"0 0 {a/2:g}"
    for k, (m, r, L, along, axis) in enumerate(links):
        child = f"link{k + 1}"
        out.append(joint_xml(k + 1, parent, child, offset, axis))
        out.append(cylinder_link_xml(child, m, r, L, along,
                                     "orange" if k % 2 == 0 else "blue"))
        parent = child
        offset = f"0 0 {L:g}" if along == "z" else f"{L:g} 0 0"
    out.append(f"""  <link name="end_effector"/>
  <joint name="end_effector_weld" type="fixed">
    <parent link="{parent}"/>
    <child link="end_effector"/>
    <origin xyz="{offset}" rpy="0 0 0"/>
  </joint>
</robot>
""")
    return "".join(out)

# (mass kg, radius m, length m, along, joint axis)
six = [(4.0, 0.06, 0.20, "z", "0 0 1"),     # shoulder yaw
       (6.0, 0.05, 0.70, "x", "0 1 0"),     # shoulder pitch, upper arm
       (5.0, 0.045, 0.60, "x", "0 1 0"),    # elbow pitch, forearm
       (1.5, 0.04, 0.12, "x", "1 0 0"),     # wrist roll
       (1.2, 0.04, 0.12, "x", "0 1 0"),     # wrist pitch
       (0.8, 0.035, 0.10, "x", "1 0 0")]    # wrist roll, tool flange
three = [(4.0, 0.06, 0.20, "z", "0 0 1"),     # shoulder yaw
         (6.0, 0.05, 0.70, "x", "0 1 0"),     # shoulder pitch, upper arm
         (5.0, 0.045, 0.60, "x", "1 0 0")]    # forearm roll: a full 3D orientation
open(MODELS / "satellite_6dof.urdf", "w").write(robot(
    "satellite_6dof", 1.0, 250.0, six,
    "A free-floating satellite (1 m cube, 250 kg) with a 6-DOF arm of cylinders "
    "(shoulder yaw-pitch, elbow pitch, wrist roll-pitch-roll); written for dacph-drake. "
    "The base has no joint: Drake makes it a free 6-DOF (quaternion) body."))
open(MODELS / "satellite_3dof.urdf", "w").write(robot(
    "satellite_3dof", 1.0, 250.0, three,
    "A 3-DOF variant for fast tests (shoulder yaw-pitch, forearm roll: the end "
    "effector's attitude has all three degrees of freedom away from a vertical upper "
    "arm); written for dacph-drake."))

"""An MJCF arm's ground truth against MuJoCo's model of the same file: the joint block
H_mm(q) of the truth's mass matrix (armature included) against MuJoCo's fixed-base M(q),
and the joints' damping, frictionloss and limits. Needs ``pip install mujoco``."""
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, Optional
import numpy as np

from dacph_drake.robots.description import MakeRobotPlant
from dacph_drake.robots.mjcf import MjcfFile
from dacph_drake.scenario import ArmBase, DescribedArm, EndEffectorFrame


@dataclass
class MujocoComparison:
    """What differs between the ground truth and MuJoCo's model (compare_with_mujoco).

    Attributes:
        joints: The arm's revolute joints.
        dofs: MuJoCo's degrees of freedom.
        mass_matrix: max |H_mm - M_mujoco| / max |M_mujoco| over the angles.
        damping: max |b - b_mujoco| [N m s/rad].
        frictionloss: max |f - f_mujoco| [N m].
        limits: max |limit - limit_mujoco| [rad]."""
    joints: int
    dofs: int
    mass_matrix: float
    damping: float
    frictionloss: float
    limits: float


def compare_with_mujoco(path: Path, end_effector: str, samples: int = 5, seed: int = 0,
                        locked_joints: Optional[Dict[str, float]] = None
                        ) -> MujocoComparison:
    """The ground truth of the MJCF arm at ``path`` against MuJoCo's model of it.

    Args:
        path: The MJCF file, as its maker ships it.
        end_effector: A frame of it (robot.end_effector.frame).
        samples: How many joint angles to compare at, uniform within limits and +-1.5 rad.
        seed: Their seed.
        locked_joints: Joints welded at a position (robot.locked_joints), also in MuJoCo."""
    import mujoco
    reference = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(reference)
    plant = MakeRobotPlant(DescribedArm(
        description=str(path), base=ArmBase(mass=100.0),
        end_effector=EndEffectorFrame(frame=end_effector),
        locked_joints=dict(locked_joints or {})))
    held = {reference.jnt_qposadr[mujoco.mj_name2id(reference, mujoco.mjtObj.mjOBJ_JOINT,
                                                    name)]: value
            for name, value in (locked_joints or {}).items()}
    joints = [joint for joint in (plant.get_joint(i) for i in plant.GetJointIndices())
              if joint.num_velocities() == 1]
    dofs = [reference.jnt_dofadr[mujoco.mj_name2id(reference, mujoco.mjtObj.mjOBJ_JOINT,
                                                   joint.name())] for joint in joints]
    v = [joint.velocity_start() for joint in joints]
    context = plant.CreateDefaultContext()
    lower = np.maximum([joint.position_lower_limits()[0] for joint in joints], -1.5)
    upper = np.minimum([joint.position_upper_limits()[0] for joint in joints], 1.5)
    mass_matrix = 0.0
    for q in np.random.default_rng(seed).uniform(lower, upper, (samples, len(joints))):
        for joint, angle in zip(joints, q, strict=True):
            joint.set_angle(context, angle)
        data.qpos[:] = reference.qpos0
        for address, value in held.items():
            data.qpos[address] = value
        data.qpos[[reference.jnt_qposadr[reference.dof_jntid[d]] for d in dofs]] = q
        mujoco.mj_forward(reference, data)
        M = np.zeros((reference.nv, reference.nv))      # row k: M e_k (M is symmetric)
        for k, unit in enumerate(np.eye(reference.nv)):
            mujoco.mj_mulM(reference, data, M[k], unit)
        M = M[np.ix_(dofs, dofs)]
        H = plant.CalcMassMatrix(context)[np.ix_(v, v)]
        mass_matrix = max(mass_matrix, float(np.abs(H - M).max() / np.abs(M).max()))
    friction = MjcfFile(Path(path)).JointAttribute("frictionloss")
    # MuJoCo's range of an unlimited joint is [0, 0]; Drake's limits are +-inf.
    ids = [reference.dof_jntid[d] for d in dofs]
    limited = reference.jnt_limited[ids].astype(bool)
    expected = np.concatenate([np.where(limited, reference.jnt_range[ids, 0], -np.inf),
                               np.where(limited, reference.jnt_range[ids, 1], np.inf)])
    limits = np.concatenate([[joint.position_lower_limits()[0] for joint in joints],
                             [joint.position_upper_limits()[0] for joint in joints]])
    return MujocoComparison(
        joints=len(joints), dofs=reference.nv, mass_matrix=mass_matrix,
        damping=float(np.max(np.abs([joint.default_damping() for joint in joints]
                                    - reference.dof_damping[dofs]))),
        frictionloss=float(np.max(np.abs([friction.get(joint.name(), 0.0)
                                          for joint in joints]
                                         - reference.dof_frictionloss[dofs]))),
        limits=float(np.max(np.where(limits == expected, 0.0,
                                     np.abs(limits - expected)))))

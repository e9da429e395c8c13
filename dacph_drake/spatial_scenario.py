"""SpatialScenario: the settings of a closed loop on a spatial free-floating robot
(a description file, description.py) tracking a 3D end-effector attitude
reference. Today it drives the model-based LHS loop (spatial_diagrams.py); the RHS
loop and the learner for spatial robots are not built yet."""
from dataclasses import dataclass, field
from typing import List

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.math import RotationMatrix
from pydrake.systems.analysis import SimulatorConfig

from dacph_drake.errors import (ConfigError, require_finite_numbers, require_in_range,
                                require_nonnegative, require_positive)
from dacph_drake.simulation import FixedStepConfig, validate_simulator_config


@dataclass
class AttitudeReference:
    """R_d(t) = R_d(0) Rot(axis, amplitude sin(2 pi t / period)) (a body-fixed
    axis), with R_d(0) the end effector's attitude at q0 turned by
    ``initial_error`` [rad] about ``initial_error_axis`` (world frame)."""
    axis: List[float] = field(default_factory=lambda: [0.0, 0.6, 0.8])
    amplitude: float = 0.4          # [rad]
    period: float = 8.0             # [s]
    initial_error: float = 0.3      # [rad]
    initial_error_axis: List[float] = field(default_factory=lambda: [0.6, 0.0, 0.8])

    def Start(self, R_WE0: RotationMatrix) -> RotationMatrix:
        """R_d(0) from the end effector's attitude at the start."""
        axis = np.asarray(self.initial_error_axis, float)
        return RotationMatrix(AngleAxis(self.initial_error,
                                        axis / np.linalg.norm(axis))) @ R_WE0

    def At(self, R_d0: RotationMatrix, t: float):
        """(R_d(t), omega_d(t) in the world frame [rad/s])."""
        axis = np.asarray(self.axis, float) / np.linalg.norm(self.axis)
        w = 2 * np.pi / self.period
        phi, phi_dot = self.amplitude * np.sin(w * t), self.amplitude * w * np.cos(w * t)
        return (R_d0 @ RotationMatrix(AngleAxis(phi, axis)),
                R_d0.matrix() @ axis * phi_dot)


@dataclass
class AttitudeGains:
    """nu = D^+ (omega_d - Lambda e) + (I - D^+ D) xi with a damped pseudo-inverse
    (``task_damping`` mu), and the sliding-mode law tau = M nu_dot + C' nu -
    damping_rate M s: the damping is scaled to the inertia (K_d = damping_rate M(q)),
    so every joint's s decays at the same rate whatever its inertia (a light wrist
    with a constant K_d would need a far faster controller than a heavy shoulder)."""
    Lambda: float = 2.0             # [1/s]
    damping_rate: float = 20.0      # [1/s]
    task_damping: float = 1e-3      # mu [-]


@dataclass
class ClearancePotential:
    """The null-space potential (spatial_potential.BaseClearancePotential):
    U = gain / 2 sum_k max(0, margin - phi_k)^2 over the link-base signed distances,
    xi = -eta grad U; gain = 0 switches it off."""
    gain: float = 1.0
    margin: float = 0.1             # [m]
    eta: float = 20.0               # [1/s]


@dataclass
class SpatialScenario:
    robot: str = "satellite_6dof"   # a shipped robot or a .urdf/.sdf path
    q0: List[float] = field(default_factory=lambda: [0.3, -0.8, 1.6, 0.2, 0.6, -0.3])
    duration: float = 8.0           # [s]
    reference: AttitudeReference = field(default_factory=AttitudeReference)
    gains: AttitudeGains = field(default_factory=AttitudeGains)
    potential: ClearancePotential = field(default_factory=ClearancePotential)
    lhs_period: float = 1e-3        # [s]
    log_period: float = 1e-2        # [s]
    simulator: SimulatorConfig = field(default_factory=FixedStepConfig)

    def Validate(self, num_joints: int) -> None:
        """ConfigError naming the first invalid setting and its allowed range."""
        if len(self.q0) != num_joints:
            raise ConfigError(f"q0 has {len(self.q0)} entries; allowed: {num_joints} "
                              "(one per joint of the robot)")
        require_finite_numbers("q0", list(self.q0))
        require_positive("duration", self.duration, "s")
        require_positive("reference.period", self.reference.period, "s")
        require_nonnegative("reference.amplitude", self.reference.amplitude, "rad")
        require_in_range("reference.initial_error", self.reference.initial_error,
                         0.0, np.pi, "rad")
        for name in ("axis", "initial_error_axis"):
            axis = getattr(self.reference, name)
            require_finite_numbers(f"reference.{name}", list(axis))
            if len(axis) != 3 or np.linalg.norm(axis) == 0:
                raise ConfigError(f"reference.{name} = {list(axis)}; allowed: a "
                                  "non-zero 3-vector")
        require_positive("gains.Lambda", self.gains.Lambda, "1/s")
        require_positive("gains.damping_rate", self.gains.damping_rate, "1/s")
        require_nonnegative("gains.task_damping", self.gains.task_damping)
        require_nonnegative("potential.gain", self.potential.gain)
        require_positive("potential.margin", self.potential.margin, "m")
        require_nonnegative("potential.eta", self.potential.eta, "1/s")
        require_positive("lhs_period", self.lhs_period, "s")
        if self.gains.damping_rate * self.lhs_period > 0.5:
            raise ConfigError(
                f"gains.damping_rate = {self.gains.damping_rate:g} 1/s with lhs_period "
                f"= {self.lhs_period:g} s; allowed: damping_rate * lhs_period <= 0.5 (the "
                "sampled sliding-mode loop stays well damped)")
        require_in_range("log_period", self.log_period, self.lhs_period, self.duration,
                         "s")
        validate_simulator_config(self.simulator)

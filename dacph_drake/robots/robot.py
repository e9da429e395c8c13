"""The Robot protocol: what a closed loop's build needs of the arm it controls,
whatever task it serves (tasks.Task); robots.planar and robots.described implement
it, assembly.robot_of picks one."""
from pathlib import Path
from typing import Callable, Dict, Optional, Protocol, Sequence, Tuple, Union

import numpy as np

from dacph_drake.errors import ConfigError


class Robot(Protocol):
    """A trial's robot, made from its scenario and its task.

    Attributes:
        scenario: The scenario.Scenario.
        task: The tasks.Task it serves.
        num_joints: n.
        model: The controller's reduced model (nominal inertias).
    """
    scenario: object
    task: object
    num_joints: int
    model: object

    @property
    def truth_plant(self) -> "MultibodyPlant":
        """The ground truth's arm as a finalized plant of its own, its default context
        holding the true inertias (for what only a simulation can measure)."""

    @classmethod
    def AddGroundTruth(cls, builder: "DiagramBuilder", trials: Sequence["Robot"]) -> Tuple[object, object]:
        """Adds the batch's ground-truth MultibodyPlant and its SceneGraph.

        Args:
            builder: The closed loop's DiagramBuilder.
            trials: Each trial's Robot.

        Returns:
            (plant, scene_graph)."""

    @classmethod
    def MakeTrueRhs(cls, plant: "MultibodyPlant", trials: Sequence["Robot"]) -> object:
        """The port's true RHS system of the batch (inputs u, state,
        disturbance_model; outputs tau, true_matrices).

        Args:
            plant: The ground-truth plant.
            trials: Each trial's Robot."""

    @classmethod
    def MakeInertialIdentifier(cls, trials: Sequence["Robot"]) -> object:
        """The batch's systems.inertial_identifier.InertialIdentifier.

        Args:
            trials: Each trial's Robot."""

    def RequireRunnableStart(self) -> None:
        """ConfigError unless a run can start at q0 (limits, clearance, step)."""

    def LimitViolation(self) -> Optional[Callable[[np.ndarray], Optional[str]]]:
        """q -> why q is beyond the joint limits (or None); None: no limits."""

    def Clearance(self) -> Optional[Callable[[np.ndarray], float]]:
        """q -> the truth's link-base clearance [m]; None: not measured."""

    def MeasuredMasses(self) -> Tuple[float, float]:
        """(total, base) [kg] as a spacecraft's mass properties give them."""

    def LiveView(self, loop: "ClosedLoop", meshcat: "Meshcat") -> object:
        """A viewers.LiveView drawing the loop's ground truth.

        Args:
            loop: The closed loop being simulated.
            meshcat: The Meshcat."""

    def WriteAnimation(self, logs: Dict[str, np.ndarray], out_html: Union[str, Path]
                       ) -> Path:
        """Writes a self-contained HTML replay of a run's logs.

        Args:
            logs: The run's logs.
            out_html: The file."""


def require_clear_start(q0: Sequence[float],
                        clearance: Optional[Callable[[np.ndarray], float]]) -> None:
    """ConfigError if q0 puts a link into the base (the truth has no contact model).

    Args:
        q0: The start [rad].
        clearance: Robot.Clearance (None: not measured)."""
    rho = clearance(np.asarray(q0, float)) if clearance is not None else np.inf
    if rho <= 0:
        raise ConfigError(f"q0 = {list(q0)} puts the arm into the base (clearance "
                          f"{rho:.3f} m); allowed: a configuration with every link "
                          "outside the base")

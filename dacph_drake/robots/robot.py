"""The Robot protocol: what a scenario's load, a sweep and a closed loop need of an arm."""
from pathlib import Path
from typing import Callable, Dict, List, Optional, Protocol, Sequence, Tuple, Union

import numpy as np

from dacph_drake.scenario.errors import ConfigError


class Robot(Protocol):
    """A trial's robot, made from its scenario and its task.

    Attributes:
        scenario: The scenario.Scenario.
        task: The tasks.Task it serves.
        num_joints: n.
        model: The controller's reduced model (nominal inertias).
        BATCH_SIZE: A sweep's trials per diagram where the sweep does not say.
        TRUTH_SAMPLES: The truth's sweep distributions it takes (ROBOT_DISTRIBUTIONS)."""
    scenario: object
    task: object
    num_joints: int
    model: object
    BATCH_SIZE: int
    TRUTH_SAMPLES: Tuple[str, ...]

    @staticmethod
    def SizedScenario(section: object, q0: Optional[Sequence[float]], task: Optional[object],
                      rows: Sequence[int]) -> Optional["Scenario"]:
        """The scenario a file naming this robot starts from, sized to it; None: defaults.

        Args:
            section: The file's robot section.
            q0: The file's q0 [rad] (None where it leaves it out).
            task: The file's task section (None where it leaves it out).
            rows: The GJM's rows that task tracks (tasks.Task.jacobian_rows)."""

    @staticmethod
    def ResolvePaths(section: object, folder: Path) -> None:
        """Makes the section's relative file paths relative to its scenario file's folder.

        Args:
            section: The robot section (changed in place).
            folder: The scenario file's folder."""

    @staticmethod
    def JointNames(section: object) -> Optional[List[str]]:
        """The names of the joints of q, in q's order (None: its joints have no names).

        Args:
            section: The robot section, its paths resolved."""

    @staticmethod
    def ApplyTruthSample(section: object, sampled: Dict[str, object]) -> None:
        """Applies a sweep trial's sampled ground truth (TRUTH_SAMPLES) to the section.

        Args:
            section: The robot section (changed in place).
            sampled: The trial's sampled settings by name."""

    @staticmethod
    def ApplyModelError(section: object, links: Optional[Sequence[float]],
                        base: Optional[float]) -> None:
        """Applies a sweep trial's model error: nominal link and base mass, inertia factors.

        Args:
            section: The robot section (changed in place).
            links: One factor per link (joint), or None.
            base: The base's factor, or None."""

    @property
    def truth_plant(self) -> "MultibodyPlant":
        """The truth's arm as its own finalized plant (default context: true inertias)."""

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
        """The batch's true RHS (in: u, state, disturbance_model; out: tau, true_matrices).

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

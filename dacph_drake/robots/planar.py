"""The planar n-link arm (scenario.PlanarArm): truth, closed-form model, clearance."""
import copy
from pathlib import Path
from typing import Callable, Dict, Optional, Sequence, Tuple, Union

import numpy as np
from pydrake.geometry import Meshcat, SceneGraph
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import DiagramBuilder

from dacph_drake.dynamics.plant import AddFreeFloatingArms, MakeArmPlant
from dacph_drake.dynamics.reduced_model import ReducedOrderModel, mass_matrix_bounds
from dacph_drake.dynamics.sensor_noise import state_noise
from dacph_drake.scenario.errors import ConfigError, require_in_range, require_positive
from dacph_drake.dynamics.base_repulsion import BaseRepulsionPotential
from dacph_drake.robots.robot import require_clear_start
from dacph_drake.robots.sizing import (LHS_DAMPING_RATE, MIN_AMPLITUDE, rhs_period,
                                      sized_disturbance, sized_uncertainty)
from dacph_drake.scenario import EndEffectorAngle, PlanarArm, Scenario
from dacph_drake.scenario.checks import validate_shared
from dacph_drake.scenario.planar_arm import RobotParams
from dacph_drake.systems.inertial_identifier import InertialIdentifier
from dacph_drake.systems.true_rhs import TrueRhs


def validate_planar_arm(arm: PlanarArm) -> int:
    """Checks a planar robot section; returns its joint count.

    Args:
        arm: The section.

    Raises:
        ConfigError: Naming the first invalid setting."""
    arm.truth.Validate("robot.truth")
    arm.nominal.Validate("robot.nominal")
    n = arm.truth.num_links
    if arm.nominal.num_links != n:
        raise ConfigError(f"robot.nominal has {arm.nominal.num_links} links; "
                          f"allowed: the same as robot.truth ({n})")
    for name in ("base_gain", "base_margin", "fold_gain"):
        require_positive(f"robot.potential.{name}", getattr(arm.potential, name))
    require_in_range("robot.potential.fold_margin", arm.potential.fold_margin, 1e-3,
                     np.pi, "rad")
    require_in_range("robot.potential.points_per_link", arm.potential.points_per_link,
                     1, 100)
    return n


class PlanarRobot:
    """robots.robot.Robot of a PlanarArm.

    Args:
        scenario: The scenario.
        task: The tasks.Task it serves.

    Raises:
        ConfigError: Naming the scenario's first invalid setting."""

    # A sweep's trials per diagram (scripts/bench_sweep.py: a planar arm's fastest per
    # trial), and the ground truth's sweep distributions it takes.
    BATCH_SIZE = 64
    TRUTH_SAMPLES = ("link_mass_scale", "link_length_scale", "link_inertia_scale",
                     "base_mass_scale", "base_inertia_scale")

    @staticmethod
    def SizedScenario(section: PlanarArm, q0: Optional[Sequence[float]],
                      task: Optional[EndEffectorAngle], rows: Sequence[int]
                      ) -> Optional[Scenario]:
        """robots.robot.Robot.SizedScenario: planar_arm_scenario; None for the paper's arm.

        Args:
            section: The file's robot section.
            q0: The file's q0 [rad] (None where it leaves it out).
            task: The file's task section (None where it leaves it out).
            rows: Unused (the planar task tracks alpha)."""
        if section.truth == RobotParams():
            return None
        return planar_arm_scenario(section, q0, task)

    @staticmethod
    def ResolvePaths(section: PlanarArm, folder: Path) -> None:
        """robots.robot.Robot.ResolvePaths: a planar arm names no file.

        Args:
            section: The robot section.
            folder: The scenario file's folder."""

    @staticmethod
    def JointNames(section: PlanarArm) -> None:
        """robots.robot.Robot.JointNames: a planar arm's joints have no names.

        Args:
            section: The robot section."""
        return None

    @staticmethod
    def ApplyTruthSample(section: PlanarArm, sampled: Dict[str, object]) -> None:
        """robots.robot.Robot.ApplyTruthSample: per link mass (and inertia), length (com,
        width; inertia squared) and inertia factors; the base's mass (and inertia), inertia.

        Args:
            section: The robot section (changed in place).
            sampled: The trial's sampled settings by name."""
        links = section.truth.links
        for link, f in zip(links, sampled.get("link_mass_scale", [1.0] * len(links))):
            link.mass *= f
            link.inertia *= f
        for link, f in zip(links, sampled.get("link_length_scale", [1.0] * len(links))):
            link.length *= f
            link.com *= f
            link.width *= f
            link.inertia *= f * f
        for link, f in zip(links, sampled.get("link_inertia_scale", [1.0] * len(links))):
            link.inertia *= f
        f = sampled.get("base_mass_scale", 1.0)
        section.truth.base.mass *= f
        section.truth.base.inertia *= f * sampled.get("base_inertia_scale", 1.0)

    @staticmethod
    def ApplyModelError(section: PlanarArm, links: Optional[Sequence[float]],
                        base: Optional[float]) -> None:
        """robots.robot.Robot.ApplyModelError: on the nominal links and base.

        Args:
            section: The robot section (changed in place).
            links: One factor per link, or None.
            base: The base's factor, or None."""
        for link, f in zip(section.nominal.links, links or []):
            link.mass *= f
            link.inertia *= f
        if base is not None:
            section.nominal.base.mass *= base
            section.nominal.base.inertia *= base

    def __init__(self, scenario: Scenario, task: "Task"):
        self.scenario, self.task = scenario, task
        self.num_joints = validate_planar_arm(scenario.robot)
        validate_shared(scenario, task, self.num_joints)
        self._model, self._bounds = None, None

    @property
    def model(self) -> ReducedOrderModel:
        if self._model is None:
            self._model = ReducedOrderModel(MakeArmPlant(self.scenario.robot.nominal))
        return self._model

    @property
    def truth_plant(self) -> MultibodyPlant:
        """The ground truth's arm as a plant of its own (MakeArmPlant of robot.truth)."""
        return MakeArmPlant(self.scenario.robot.truth)

    @property
    def mass_matrix_bounds(self):
        """(inf_q lambda_min(M), sup_q lambda_max(M)) of the nominal robot."""
        if self._bounds is None:
            self._bounds = mass_matrix_bounds(self.model)
        return self._bounds

    @classmethod
    def AddGroundTruth(cls, builder: DiagramBuilder, trials: Sequence["PlanarRobot"]
                       ) -> Tuple[MultibodyPlant, SceneGraph]:
        """A plant of every trial's true arm (AddFreeFloatingArms): (plant, scene_graph).

        Args:
            builder: The closed loop's builder.
            trials: Each trial's Robot (one: a single run)."""
        return AddFreeFloatingArms(builder, [t.scenario.robot.truth for t in trials])

    @classmethod
    def MakeTrueRhs(cls, plant: MultibodyPlant, trials: Sequence["PlanarRobot"]
                    ) -> TrueRhs:
        """Makes the port's true RHS of the trials' arms (systems.true_rhs.TrueRhs).

        Args:
            plant: The trials' ground-truth plant (AddGroundTruth).
            trials: Each trial's Robot."""
        return TrueRhs(plant=plant, truths=[t.scenario.robot.truth for t in trials],
                       uncertainties=[t.scenario.uncertainty for t in trials],
                       phases=[t.scenario.phases for t in trials])

    def RequireRunnableStart(self) -> None:
        """ConfigError unless every true link clears the base at q0, the task regular."""
        require_clear_start(self.scenario.q0, self.Clearance())
        self.task.RequireRegularStart(self)

    @classmethod
    def MakeInertialIdentifier(cls, trials: Sequence["PlanarRobot"]) -> InertialIdentifier:
        """The batch's InertialIdentifier on the nominal plants.

        Args:
            trials: Each trial's Robot."""
        scenario = trials[0].scenario
        return InertialIdentifier(
            plants=[t.model.plant for t in trials], settings=scenario.inertia,
            period=scenario.periods.learner_sample,
            error_period=scenario.periods.learner, seeds=[t.scenario.seed for t in trials],
            measured_masses=[t.MeasuredMasses() for t in trials],
            noise=state_noise(scenario.sensing, scenario.periods.rhs))

    def LimitViolation(self) -> Optional[Callable[[np.ndarray], Optional[str]]]:
        """The check of the robot's position limits: None (the joints turn freely)."""
        return None                 # the planar arm's joints turn freely

    def Clearance(self) -> Optional[Callable[[np.ndarray], float]]:
        """q -> the smallest clearance [m] of the true arm's links from the base."""
        return BaseRepulsionPotential(self.scenario.robot.truth,
                                      self.scenario.robot.potential).MinClearance

    def LiveView(self, loop: "ClosedLoop", meshcat: Meshcat) -> "viewers.LiveView":
        """A viewers.LiveView drawing the loop's ground truth (LiveView.ForPlanarLoop).

        Args:
            loop: The closed loop (of this robot) being simulated.
            meshcat: The Meshcat to draw into."""
        from dacph_drake.robots.viewers import LiveView
        return LiveView.ForPlanarLoop(loop, meshcat)

    def WriteAnimation(self, logs: Dict[str, np.ndarray], out_html: Union[str, Path]
                       ) -> Path:
        """Writes a run's HTML replay (viewers.write_animation); returns its path.

        Args:
            logs: The run's logs (RunResult.logs).
            out_html: The HTML file to write."""
        from dacph_drake.robots.viewers import write_animation
        return write_animation(self.scenario, logs, out_html)

    def MeasuredMasses(self) -> Tuple[float, float]:
        """(total, base) mass [kg] of the true arm."""
        truth = self.scenario.robot.truth
        return (truth.base.mass + sum(link.mass for link in truth.links),
                float(truth.base.mass))


def planar_arm_scenario(robot: PlanarArm, q0: Optional[Sequence[float]] = None,
                        task: Optional[EndEffectorAngle] = None) -> Scenario:
    """The scenario of a planar arm of any number of links: uncertainty and disturbance from
    the true joint inertias at q0 and the reference's rates; without a task, K_d = Kd I at
    most LHS_DAMPING_RATE inf_q lambda_min(M) (the sampled LHS loop stays well damped with
    light distal links); periods.rhs shortened where the gain rule asks (rhs_period: c
    grows as Kd / inf lambda_min); otherwise the paper's settings.

    Args:
        robot: The robot section (the defaults' nominal arm: a copy of its truth).
        q0: The start (default: the paper's q1 = 0.3 rad, its elbow's 1 rad spread evenly).
        task: The task (default EndEffectorAngle(): the paper's reference and gains)."""
    n = robot.truth.num_links
    robot = copy.deepcopy(robot)
    robot.nominal = copy.deepcopy(robot.truth)
    validate_planar_arm(robot)  # names a bad link before its plant is built
    nominal = ReducedOrderModel(MakeArmPlant(robot.nominal))
    if task is None:
        task = EndEffectorAngle()
        task.gains.Kd = min(task.gains.Kd,
                            LHS_DAMPING_RATE * mass_matrix_bounds(nominal)[0])
    q0 = np.asarray([0.3] + [1.0 / max(n - 1, 1)] * (n - 1) if q0 is None else q0,
                    float)
    scenario = Scenario(robot=robot, task=task, q0=[float(x) for x in q0])
    if len(q0) != n:
        return scenario         # Validate names q0's length; nothing to size by
    reference = task.reference
    amplitudes = np.maximum(np.asarray(reference.amplitudes, float), 0.0)
    periods = np.asarray(reference.periods, float)
    if not (len(periods) and np.all(periods > 0) and len(amplitudes) == len(periods)):
        return scenario         # Validate names the reference's problem
    if not np.any(amplitudes > 0):
        amplitudes = np.full_like(periods, MIN_AMPLITUDE / len(periods))
    rate = float(np.sum(2 * np.pi * amplitudes / periods))
    acceleration = float(np.sum(amplitudes * (2 * np.pi / periods) ** 2))
    inertia = np.diag(nominal.MassMatrix(q0))   # the defaults' nominal is the truth
    scenario.uncertainty = sized_uncertainty(inertia, inertia * rate)
    scenario.disturbance = sized_disturbance(inertia * acceleration)
    scenario.periods.rhs = rhs_period(scenario, nominal)
    return scenario

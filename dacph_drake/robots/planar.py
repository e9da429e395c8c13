"""The planar n-link arm (scenario.PlanarArm): the ground truth built directly
(dynamics/plant.py), the controller's closed-form reduced model with its compiled
kernels (reduced_model.ReducedOrderModel) and the kinematic base-repulsion clearance."""
from pathlib import Path
from typing import Callable, Dict, Optional, Sequence, Tuple, Union

import numpy as np
from pydrake.geometry import Meshcat, SceneGraph
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import DiagramBuilder

from dacph_drake.dynamics.plant import AddFreeFloatingArms, MakeArmPlant
from dacph_drake.dynamics.reduced_model import ReducedOrderModel, mass_matrix_bounds
from dacph_drake.errors import ConfigError, require_in_range, require_positive
from dacph_drake.robots.base_repulsion import BaseRepulsionPotential
from dacph_drake.robots.robot import require_clear_start
from dacph_drake.scenario import PlanarArm, Scenario
from dacph_drake.scenario.checks import validate_shared
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
        """Adds one plant of every trial's true arm (AddFreeFloatingArms); returns
        (plant, scene_graph).

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
        """ConfigError unless every true link is outside the base at q0 and the
        task is regular there (Task.RequireRegularStart)."""
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
            measured_masses=[t.MeasuredMasses() for t in trials])

    def LimitViolation(self) -> Optional[Callable[[np.ndarray], Optional[str]]]:
        """The check of the robot's position limits: None (the joints turn freely)."""
        return None                 # the planar arm's joints turn freely

    def Clearance(self) -> Optional[Callable[[np.ndarray], float]]:
        """q -> the smallest clearance [m] of the true arm's links from the base, for the
        run's monitor."""
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
        """Writes a self-contained HTML replay of a run's logs (viewers.write_animation);
        returns its path.

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

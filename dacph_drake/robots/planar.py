"""The planar n-link arm (scenario.PlanarArm) tracking its end effector's angle
(scenario.EndEffectorAngle): the ground truth built directly (dynamics/plant.py), the
controller's closed-form reduced model with its compiled kernels
(reduced_model.ReducedOrderModel), the kinematic base-repulsion potential, and the
sliding-mode LhsController."""
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Dict, Optional, Sequence, Tuple, Union

import numpy as np
from pydrake.geometry import Meshcat, SceneGraph
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import DiagramBuilder

from dacph_drake.errors import ConfigError
from dacph_drake.dynamics.inertial_parameters import InertialParameters
from dacph_drake.log_layout import LhsLog
from dacph_drake.dynamics.plant import AddFreeFloatingArms, ArmCoordinates, MakeArmPlant
from dacph_drake.robots import require_clear_start
from dacph_drake.robots.base_repulsion import BaseRepulsionPotential
from dacph_drake.dynamics.reduced_model import ReducedOrderModel, mass_matrix_bounds
from dacph_drake.tasks.reference import OrientationReference
from dacph_drake.scenario import Excitation, Scenario
from dacph_drake.systems.inertial_identifier import InertialIdentifier
from dacph_drake.systems.lhs_controller import (LhsController, LhsTrial,
                                                boundary_layer_per_chi)
from dacph_drake.systems.true_rhs import TrueRhs

if TYPE_CHECKING:
    from dacph_drake.analysis.verify import LhsSide
    from dacph_drake.loop.closed_loop import ClosedLoop, ControllerBuilder
    from dacph_drake.robots import viewers


class PlanarRobot:
    """robots.Robot for a scenario whose robot is a PlanarArm.

    Args:
        scenario: The scenario (its robot a scenario.PlanarArm, its task a
            scenario.EndEffectorAngle).

    Raises:
        ConfigError: Naming the scenario's first invalid setting."""
    lhs_name, lhs_log = "lhs_controller", "lhs_log"
    task_panels = ("e_dac_vs_model_based", "f_inputs_and_states")

    def __init__(self, scenario: Scenario):
        self.scenario = scenario
        self.num_joints = scenario.robot.Validate()
        scenario.ValidateShared(self.num_joints)
        self._model, self._bounds = None, None

    @property
    def model(self) -> ReducedOrderModel:
        if self._model is None:
            self._model = ReducedOrderModel(MakeArmPlant(self.scenario.robot.nominal))
        return self._model

    @property
    def mass_matrix_bounds(self):
        """(inf_q lambda_min(M), sup_q lambda_max(M)) of the nominal robot."""
        if self._bounds is None:
            self._bounds = mass_matrix_bounds(self.model)
        return self._bounds

    @classmethod
    def AddGroundTruth(cls, builder: DiagramBuilder, trials: Sequence["PlanarRobot"]
                       ) -> Tuple[MultibodyPlant, SceneGraph]:
        """Adds one plant of every trial's true arm (AddFreeFloatingArms).

        Args:
            builder: The closed loop's builder.
            trials: Each trial's Robot (one: a single run).

        Returns:
            (plant, scene_graph)."""
        return AddFreeFloatingArms(builder, [t.scenario.robot.truth for t in trials])

    @classmethod
    def MakeTrueRhs(cls, plant: MultibodyPlant, trials: Sequence["PlanarRobot"]
                    ) -> TrueRhs:
        """Makes the port's true RHS of the trials' arms (systems.true_rhs.TrueRhs).

        Args:
            plant: The trials' ground-truth plant (AddGroundTruth).
            trials: Each trial's Robot.

        Returns:
            The TrueRhs, with each trial's truth, uncertainty and phases."""
        return TrueRhs(plant=plant, truths=[t.scenario.robot.truth for t in trials],
                       uncertainties=[t.scenario.uncertainty for t in trials],
                       phases=[t.scenario.phases for t in trials])

    def RequireRunnableStart(self) -> None:
        """Requires that a run can start at the scenario's q0.

        Every link of the ground-truth arm lies outside the base at q0 (clearance of
        the link outline > 0, as robots.base_repulsion.BaseRepulsionPotential
        measures it), and the controller's task Jacobian D(q0) (1 x n,
        d alpha / d qdot) is far enough from singular for D+ = D^T / (D D^T):
        ||D(q0)|| >= task.gains.min_task_singular_value.

        Raises:
            ConfigError: q0 puts the arm into the base, or is near a singularity
                of D."""
        scenario = self.scenario
        q0 = np.asarray(scenario.q0, float)
        require_clear_start(scenario.q0, self.Clearance())
        sigma = float(np.linalg.norm(self.model.Evaluate(q0, np.zeros_like(q0)).D))
        bound = scenario.task.gains.min_task_singular_value
        if sigma < bound:
            raise ConfigError(
                f"q0 = {list(scenario.q0)} is near a singularity of the task Jacobian D "
                f"(||D(q0)|| = {sigma:.3g}); allowed: a q0 with ||D(q0)|| >= "
                f"task.gains.min_task_singular_value = {bound:g}")

    def GainRuleRates(self) -> Tuple[float, float]:
        """The LHS's rates for eq. (48): K_d = Kd I.

        Returns:
            (Kd, the nominal robot's inf_q lambda_min(M))."""
        return self.scenario.task.gains.Kd, self.mass_matrix_bounds[0]

    @classmethod
    def AddLhsController(cls, controller: "ControllerBuilder",
                         trials: Sequence["PlanarRobot"], excitation: Excitation,
                         identify: bool) -> Dict:
        """Adds the LhsController of the trials into the controller's builder.

        Each trial has its nominal robot's potential, theta0(0) = 0.

        Args:
            controller: The controller's ControllerBuilder.
            trials: Each trial's Robot.
            excitation: The learner's excitation tau_pe(t) (amplitude 0: off).
            identify: Feed the LhsController from an InertialIdentifier
                (scenario.inertia).

        Returns:
            The named systems added (system name -> system)."""
        scenario, builder = trials[0].scenario, controller.builder
        identifier = (builder.AddNamedSystem("inertial_identifier", InertialIdentifier(
            plants=[t.model.plant for t in trials], settings=scenario.inertia,
            period=scenario.periods.learner_sample,
            measured_masses=[t.MeasuredMasses() for t in trials])) if identify else None)
        lhs = builder.AddNamedSystem(cls.lhs_name, LhsController(
            trials=[LhsTrial(
                model=t.model, potential=BaseRepulsionPotential(
                    t.scenario.robot.nominal, t.scenario.robot.potential),
                reference=OrientationReference(t.scenario.task.reference,
                                               float(np.sum(t.scenario.q0))),
                lambda_min_M=t.GainRuleRates()[1]) for t in trials],
            gains=scenario.task.gains, period=scenario.periods.lhs,
            excitation=excitation,
            identify=identify))
        for signal in ("base_pose", "q", "qdot"):
            controller.Input(lhs.GetInputPort(signal), signal)
        return {cls.lhs_name: lhs, **({"inertial_identifier": identifier}
                                      if identify else {})}

    def LimitViolation(self) -> Optional[Callable[[np.ndarray], Optional[str]]]:
        """The check of the robot's position limits: none.

        Returns:
            None: the planar arm's joints turn freely."""
        return None                 # the planar arm's joints turn freely

    def Clearance(self) -> Optional[Callable[[np.ndarray], float]]:
        """The ground truth's link-base clearance, for the run's monitor.

        Returns:
            q -> the smallest clearance of the true arm's links from the base [m]."""
        return BaseRepulsionPotential(self.scenario.robot.truth,
                                      self.scenario.robot.potential).MinClearance

    def LiveView(self, loop: "ClosedLoop", meshcat: Meshcat) -> "viewers.LiveView":
        """Makes a viewers.LiveView drawing the loop's ground truth.

        Made by LiveView.ForPlanarLoop.

        Args:
            loop: The closed loop (of this robot) being simulated.
            meshcat: The Meshcat to draw into.

        Returns:
            The LiveView."""
        from dacph_drake.robots.viewers import LiveView
        return LiveView.ForPlanarLoop(loop, meshcat)

    def WriteAnimation(self, logs: Dict[str, np.ndarray], out_html: Union[str, Path]
                       ) -> Path:
        """Writes a self-contained HTML replay of a run's logs.

        Written by viewers.write_animation.

        Args:
            logs: The run's logs (RunResult.logs).
            out_html: The HTML file to write.

        Returns:
            The HTML file's path."""
        from dacph_drake.robots.viewers import write_animation
        return write_animation(self.scenario, logs, out_html)

    def TaskSignals(self, logs: Dict[str, np.ndarray]) -> Tuple[np.ndarray, ...]:
        """The task's signals over time, for metrics.run_metrics.

        Args:
            logs: The run's logs (RunResult.logs).

        Returns:
            (alpha~ [rad], s (n columns), the kinematic clearance of the ground
                truth [m], theta0 - theta0(0) [rad])."""
        n = self.num_joints
        lhs, L = logs["lhs_log"], LhsLog(n)
        base_pose, q, _, _ = ArmCoordinates.ForPlanarArm(n).Split(logs["state"])
        clearance = self.Clearance()
        return (lhs[:, L.alpha_error], lhs[:, L.s],
                np.array([clearance(joints) for joints in q]),
                base_pose[:, 2] - base_pose[0, 2])

    def TaskMetrics(self, logs: Dict[str, np.ndarray]) -> Dict[str, float]:
        """The task's own metrics beside metrics.run_metrics' shared ones: none.

        None beyond the common metrics (analysis.metrics) for the planar task.

        Args:
            logs: The run's logs (RunResult.logs).

        Returns:
            An empty dictionary."""
        return {}

    def MeasuredMasses(self) -> Tuple[float, float]:
        """The ground truth's total and base mass, as a spacecraft's mass
        properties give them (the identifier's anchor, scenario.inertia).

        Returns:
            (total, base) [kg]."""
        return self.TotalMass(), float(self.scenario.robot.truth.base.mass)

    def TotalMass(self) -> float:
        """The true arm's total mass, base and links.

        Returns:
            The mass [kg]."""
        truth = self.scenario.robot.truth
        return truth.base.mass + sum(link.mass for link in truth.links)

    def VerifyLhs(self, logs: Dict[str, np.ndarray], region_budget: float
                  ) -> "LhsSide":
        """What dacph verify checks of this LHS.

        V is s^T M s / 2 with the M the controller ran on: the nominal robot's
        until the inertial identifier's start, the identified one's after it
        (logs["inertial_parameters"]); the envelope and eq. (45) take the inertia
        bounds of both (the smallest inf lambda_min, the largest sup lambda_max).

        Args:
            logs: The run's logs (RunResult.logs).
            region_budget: The wall time [s] after which the region of
                attraction's program is stopped.

        Returns:
            The analysis.verify.LhsSide."""
        from dacph_drake.analysis.lyapunov_envelope import EnvelopeConstants
        from dacph_drake.analysis.region_of_attraction import sliding_region_of_attraction
        from dacph_drake.analysis.verify import LhsSide
        scenario, n, model = self.scenario, self.num_joints, self.model
        models = [model]
        if "inertial_parameters" in logs:
            models.append(model.WithInertialParameters(
                InertialParameters(model.plant), logs["inertial_parameters"][-1]))
        bounds = np.array([mass_matrix_bounds(m) for m in models])
        lambda_min_M, lambda_max_M = float(bounds[:, 0].min()), float(bounds[:, 1].max())
        gains = scenario.task.gains
        Kd, epsilon = gains.Kd, gains.epsilon
        # The boundary layer as the controller built it, from the nominal robot's bound.
        layer_per_chi = boundary_layer_per_chi(gains, bounds[0, 0])
        L = LhsLog(n)
        return LhsSide(
            V=logs["lhs_log"][:, L.lyapunov_V],
            s0_norm=float(np.linalg.norm(logs["lhs_log"][0, L.s])),
            constants=EnvelopeConstants.ForConstantDamping(
                Kd, Kd, lambda_min_M, lambda_max_M, epsilon, n, layer_per_chi),
            lambda_lhs=2 * Kd / lambda_min_M,
            region=sliding_region_of_attraction(
                model, np.asarray(scenario.q0), Kd, scenario.rhs.chi_initial,
                epsilon + layer_per_chi * scenario.rhs.chi_initial, region_budget),
            settings={"inf_lambda_min_M": lambda_min_M, "sup_lambda_max_M": lambda_max_M,
                      "models": len(models)})

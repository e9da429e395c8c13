"""An arm from a description file (scenario.DescribedArm: URDF/SDF, the root body
the free base) tracking its end effector's 3D attitude
(scenario.EndEffectorAttitude): the description parsed once per diagram
(description.ParsedDescription) into the ground truth's plant, which the
controller's model evaluates in contexts of its own with its inertias scaled
(floating_model.FloatingBaseModel) and the clearance potential queries with its
collision geometry; and the AttitudeController."""
import copy
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Dict, Optional, Sequence, Tuple, Union

import numpy as np
from pydrake.geometry import Meshcat, SceneGraph
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import DiagramBuilder

from dacph_drake.errors import ConfigError
from dacph_drake.robots import require_clear_start
from dacph_drake.robots.description import ParsedDescription
from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.dynamics.inertial_parameters import PER_BODY, InertialParameters
from dacph_drake.dynamics.kinematic_tree import KinematicTree
from dacph_drake.log_layout import AttitudeLog
from dacph_drake.dynamics.plant import AddClonedArms, ArmCoordinates
from dacph_drake.scenario import ClearancePotential, Excitation, Scenario
from dacph_drake.robots.clearance_potential import BaseClearancePotential
from dacph_drake.robots.start_pose import task_singularity
from dacph_drake.systems.attitude_controller import AttitudeController, AttitudeTrial
from dacph_drake.systems.inertial_identifier import InertialIdentifier
from dacph_drake.systems.spatial_true_rhs import SpatialTrueRhs

if TYPE_CHECKING:
    from dacph_drake.analysis.verify import LhsSide
    from dacph_drake.loop.closed_loop import ClosedLoop, ControllerBuilder
    from dacph_drake.robots import viewers

SETTLING_TIME = 1.0             # [s] left out of the steady-state error metrics
# Configurations sampled for sup_q max_i M_ii of the arm in VerifyLhs, and the
# margin on the largest sample. It enters only the envelope's lower bound (a faster
# allowed decay), so an underestimate can flag a false violation, never hide one.
DIAGONAL_SAMPLES, DIAGONAL_MARGIN = 256, 0.1


def arm_joints(model: FloatingBaseModel) -> list:
    """The plant's joints of an arm's joint angles q, in q's order.

    Args:
        model: The arm's model.

    Returns:
        The pydrake joints."""
    plant = model.plant
    joints = {plant.get_joint(j).position_start(): plant.get_joint(j)
              for j in plant.GetJointIndices() if plant.get_joint(j).num_positions() == 1}
    return [joints[int(i)] for i in model.coordinates.joint_q]


def model_error_scale(arm: "DescribedArm", links: Optional[Sequence[float]],
                      base: Optional[float]) -> list:
    """robot.nominal_inertia_scale for a sweep's model-error sample, in the plant's
    body order: ``base`` on the free base's body, links[j] on the body joint j moves
    (its child), 1 on every other body (a welded tool, a locked finger, a mounted
    description's own root); an entry left out is 1.

    Args:
        arm: The robot section (its description is parsed once per process and
            section).
        links: One factor per joint, or None.
        base: The base body's factor, or None.

    Returns:
        One factor per body with mass."""
    names, base_index, child_index = _body_roles(arm)
    scale = [1.0] * len(names)
    if base is not None:
        scale[base_index] = float(base)
    for j, factor in zip(child_index, links or []):
        if j is not None:
            scale[j] = float(factor)
    return scale


_BODY_ROLES: Dict[str, Tuple[list, int, list]] = {}


def _body_roles(arm: "DescribedArm") -> Tuple[list, int, list]:
    """(body names with mass in the plant's order, the free base's index, each
    joint's child's index or None where that body has no mass), cached per robot
    section (its model error left out: the bodies do not depend on it)."""
    section = copy.copy(arm)
    section.nominal_inertia_scale = []
    key = repr(section)
    if key not in _BODY_ROLES:
        model = FloatingBaseModel(ParsedDescription(section).plant)
        bodies = [body.name() for body in model.parameters.bodies]
        plant = model.plant
        base = plant.get_body(next(iter(plant.GetFloatingBaseBodies()))).name()
        children = [joint.child_body().name() for joint in arm_joints(model)]
        _BODY_ROLES[key] = (bodies, bodies.index(base),
                            [bodies.index(c) if c in bodies else None for c in children])
    return _BODY_ROLES[key]


def require_every_joint_moves_inertia(model: FloatingBaseModel, description: str
                                      ) -> None:
    """Requires every actuated joint of a described arm to move some inertia.

    A joint whose outboard bodies have no mass and no rotational inertia about its
    axis has M_jj = 0: M(q) is singular, and the gain rule's bound, the sizing
    rule's scales and the port's momentum are undefined.

    Args:
        model: The arm's model.
        description: The robot's description, for the message.

    Raises:
        ConfigError: Naming the first such joint."""
    diagonal = np.diag(model.MassMatrix(np.zeros(model.num_joints)))
    idle = np.flatnonzero(diagonal <= 1e-9 * max(float(np.max(diagonal)), 1e-300))
    if len(idle):
        raise ConfigError(
            f"robot.description {description!r}: joint "
            f"{arm_joints(model)[idle[0]].name()!r} moves no inertia (the bodies beyond "
            "it have no mass and no rotational inertia about its axis); allowed: a "
            "description whose every actuated joint moves a body with mass, or "
            "robot.locked_joints naming that joint")


# [s] the shortest ground-truth step a run takes (4.95 us was the family's shortest
# that ran, in 245 s for a 14 s run).
MIN_TRUTH_STEP = 1e-6
# [m] how far the clearance the monitor checks (DescribedRobot.Clearance) is measured:
# it asks only whether a link touches the base.
CONTACT_QUERY = 0.01
# The base joint's coordinates (qw, qx, qy, qz, x, y, z) at the origin: link-base
# distances do not depend on them.
_BASE_AT_REST = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])


class DescribedRobot:
    """robots.Robot for a scenario whose robot is a DescribedArm.

    Args:
        scenario: The scenario (its robot a scenario.DescribedArm, its task a
            scenario.EndEffectorAttitude).

    Raises:
        ConfigError: Naming the scenario's first invalid setting, or what its
            description has that is not allowed."""
    lhs_name, lhs_log = "attitude_controller", "attitude_log"
    task_panels = ("e_attitude_dac_vs_model_based",)

    def __init__(self, scenario: Scenario):
        self.scenario = scenario
        arm = scenario.robot
        arm.ValidateAssembly()
        self.parsed = ParsedDescription(arm)
        self.model = FloatingBaseModel(self.parsed.plant)
        self.num_joints = self.model.num_joints
        require_every_joint_moves_inertia(self.model, arm.description)
        arm.Validate([body.name() for body in self.model.parameters.bodies])
        scenario.ValidateShared(self.num_joints,
                                [joint.name() for joint in arm_joints(self.model)])
        if arm.nominal_inertia_scale:
            self.model.SetInertialParameters(self.model.inertial_parameters * np.repeat(
                arm.nominal_inertia_scale, PER_BODY))

    @property
    def truth_plant(self) -> MultibodyPlant:
        """The ground truth's plant.

        Its default context holds the description's inertias; the controller's model
        evaluates it with its own."""
        return self.parsed.plant

    @classmethod
    def AddGroundTruth(cls, builder: DiagramBuilder, trials: Sequence["DescribedRobot"]
                       ) -> Tuple[MultibodyPlant, SceneGraph]:
        """Adds the ground-truth plant of a batch and its SceneGraph.

        One trial: its parsed plant and SceneGraph (ParsedDescription.AddTo: the
        description is parsed once per diagram). A batch: one plant holding a copy
        of each trial's arm (plant.AddClonedArms), whose dynamics are the parsed
        plant's bit for bit.

        Args:
            builder: The closed loop's builder.
            trials: Each trial's Robot (one: a single run).

        Returns:
            (plant, scene_graph).

        Raises:
            ConfigError: The trials' arms differ in their kinematic tree."""
        if len(trials) == 1:
            return trials[0].parsed.AddTo(builder)
        _RequireOneTree(trials)
        return AddClonedArms(builder, [trial.parsed.plant for trial in trials])

    @classmethod
    def MakeTrueRhs(cls, plant: MultibodyPlant, trials: Sequence["DescribedRobot"]
                    ) -> SpatialTrueRhs:
        """Makes the port's true RHS of the trials' arms.

        A systems.spatial_true_rhs.SpatialTrueRhs.

        Args:
            plant: The trials' ground-truth plant (AddGroundTruth).
            trials: Each trial's Robot.

        Returns:
            The SpatialTrueRhs, with each trial's parsed plant, uncertainty and
                phases."""
        return SpatialTrueRhs(plant=plant, arms=[trial.parsed.plant for trial in trials],
                              uncertainties=[t.scenario.uncertainty for t in trials],
                              phases=[t.scenario.phases for t in trials])

    def RequireRunnableStart(self) -> None:
        """Requires that a run can start at the scenario's q0.

        q0 must lie within the description's joint limits (robot.joint_limits
        "stop"), with every link's collision geometry outside the base's
        (Clearance).

        The ground truth's step must be at least MIN_TRUTH_STEP: a description
        whose joint damping over its inertia asks for less (18 N m s/rad on a 6 g
        link: 0.12 us, 1e8 steps for a 14 s run) is named instead of run for hours.

        Raises:
            ConfigError: Naming the first joint beyond its limits, q0 putting a
                link into the base, or the step and the most damped joint."""
        step = self.scenario.simulator.max_step_size
        if step < MIN_TRUTH_STEP:
            damping = self.model.joint_damping
            rates = damping / np.diag(self.model.MassMatrix(np.asarray(
                self.scenario.q0, float)))
            k = int(np.argmax(rates))
            raise ConfigError(
                f"simulator.max_step_size = {step:.3g} s, the step the description's "
                f"joint damping asks for (joint {arm_joints(self.model)[k].name()!r}: "
                f"{damping[k]:g} N m s/rad on {damping[k] / rates[k]:.3g} kg m^2); "
                f"allowed: >= {MIN_TRUTH_STEP:g} s: robot.joint_damping: zero, or a "
                "description with less damping on its light joints")
        violation = self.LimitViolation()
        reason = violation(np.asarray(self.scenario.q0, float)) if violation else None
        if reason:
            raise ConfigError(f"q0 = {list(self.scenario.q0)}: {reason}; allowed: a q0 "
                              "within the limits, or robot.joint_limits: ignore")
        singular = task_singularity(self.model, self.scenario.q0)
        if singular:
            raise ConfigError(f"q0 = {list(self.scenario.q0)}: {singular}; allowed: a "
                              "q0 away from the task's singularities, or none (a start "
                              "is then chosen: robots.start_pose.choose_start)")
        require_clear_start(self.scenario.q0, self.Clearance())

    def LimitViolation(self) -> Optional[Callable[[np.ndarray], Optional[str]]]:
        """The check of the description's joint limits, for the run's monitor.

        Returns:
            With robot.joint_limits "stop" and finite limits: q -> "joint NAME at X
                rad beyond [LOWER, UPPER] rad" for the first joint out of its limits,
                or None; otherwise None."""
        if self.scenario.robot.joint_limits != "stop":
            return None
        arm = arm_joints(self.model)
        names = [joint.name() for joint in arm]
        lower = np.array([joint.position_lower_limits()[0] for joint in arm])
        upper = np.array([joint.position_upper_limits()[0] for joint in arm])
        if not (np.any(np.isfinite(lower)) or np.any(np.isfinite(upper))):
            return None

        def violation(q):
            outside = np.flatnonzero((q < lower) | (q > upper))
            if not len(outside):
                return None
            k = outside[0]
            return (f"joint {names[k]!r} at {q[k]:.4f} rad beyond its limits "
                    f"[{lower[k]:.4f}, {upper[k]:.4f}] rad")
        return violation

    def GainRuleRates(self) -> Tuple[float, float]:
        """The LHS's rates for eq. (48), with K_d = damping_rate M(q).

        The LHS rate lambda_max(K_d) / inf lambda_min(M) is damping_rate for every
        arm (gain_rule.inertia_scaled_c_lower_bound).

        Returns:
            (damping_rate, 1.0)."""
        return self.scenario.task.gains.damping_rate, 1.0

    @classmethod
    def AddLhsController(cls, controller: "ControllerBuilder",
                         trials: Sequence["DescribedRobot"], excitation: Excitation,
                         identify: bool) -> Dict:
        """Adds the AttitudeController of the trials into the controller's builder.

        Each trial has its clearance potential unless its gain is 0.

        Args:
            controller: The controller's ControllerBuilder.
            trials: Each trial's Robot.
            excitation: The learner's excitation tau_pe(t) (amplitude 0: off).
            identify: Feed the AttitudeController from an InertialIdentifier
                (scenario.inertia).

        Returns:
            The named systems added (system name -> system)."""
        first = trials[0].scenario
        builder, arm = controller.builder, first.robot
        lhs = builder.AddNamedSystem(cls.lhs_name, AttitudeController(
            trials=[AttitudeTrial(model=trial.model, potential=trial._Potential(),
                                  q0=trial.scenario.q0) for trial in trials],
            reference=first.task.reference, gains=first.task.gains,
            period=first.periods.lhs, eta=arm.potential.eta, excitation=excitation,
            identify=identify))
        for signal in ("base_pose", "base_velocity", "q", "qdot"):
            controller.Input(lhs.GetInputPort(signal), signal)
        if not identify:
            return {cls.lhs_name: lhs}
        identifier = builder.AddNamedSystem("inertial_identifier", InertialIdentifier(
            plants=[trial.model.plant for trial in trials],
            priors=[trial.model.inertial_parameters for trial in trials],
            settings=first.inertia, period=first.periods.learner_sample,
            measured_masses=[trial.MeasuredMasses() for trial in trials]))
        return {cls.lhs_name: lhs, "inertial_identifier": identifier}

    def _Potential(self) -> Optional[BaseClearancePotential]:
        """The link-base clearance potential of this trial's arm (None with a zero
        gain)."""
        arm = self.scenario.robot
        return (BaseClearancePotential(parsed=self.parsed, model=self.model,
                                       gain=arm.potential.gain, margin=arm.potential.margin)
                if arm.potential.gain > 0 else None)

    def Clearance(self) -> Optional[Callable[[np.ndarray], float]]:
        """The ground truth's link-base clearance, for the run's monitor and the
        start's check.

        The smallest signed distance between a link's collision geometry and the
        base's, measured as the clearance potential measures it (with its own
        contexts; it depends on q alone), reported as inf beyond CONTACT_QUERY.

        Returns:
            q -> the clearance [m]."""
        return link_base_clearance(self.parsed, self.model, CONTACT_QUERY)

    def LiveView(self, loop: "ClosedLoop", meshcat: Meshcat) -> "viewers.LiveView":
        """Makes a viewers.LiveView drawing the loop's ground truth.

        Through a SpatialViewer, with R_d(t) from the loop's AttitudeController.

        Args:
            loop: The closed loop (of this robot) being simulated.
            meshcat: The Meshcat to draw into.

        Returns:
            The LiveView."""
        from dacph_drake.robots.viewers import LiveView, SpatialViewer
        viewer = SpatialViewer(self.scenario.robot, meshcat)
        controller = loop.systems[self.lhs_name]
        return LiveView(loop.plant, meshcat, lambda root_context, x, t: viewer.Draw(
            x, controller.DesiredAttitude(t)[0]))

    def WriteAnimation(self, logs: Dict[str, np.ndarray], out_html: Union[str, Path]
                       ) -> Path:
        """Writes a self-contained HTML replay of a run's logs.

        Written by viewers.write_spatial_animation.

        Args:
            logs: The run's logs (RunResult.logs).
            out_html: The HTML file to write.

        Returns:
            The HTML file's path."""
        from dacph_drake.robots.viewers import write_spatial_animation
        return write_spatial_animation(self.scenario.robot, logs, out_html)

    def TaskSignals(self, logs: Dict[str, np.ndarray]) -> Tuple[np.ndarray, ...]:
        """The task's signals over time, for metrics.run_metrics.

        Args:
            logs: The run's logs (RunResult.logs).

        Returns:
            (|e| [rad], ||s||, the signed link-base distance (attitude_log) [m],
                the angle of the base's rotation from its start [rad])."""
        log, A = logs["attitude_log"], AttitudeLog()
        base_q = ArmCoordinates.FromPlant(self.model.plant).base_q
        quaternion = logs["state"][:, base_q[:4]]       # the free base's (w, x, y, z)
        quaternion = quaternion / np.linalg.norm(quaternion, axis=1, keepdims=True)
        cosine = np.clip(np.abs(quaternion @ quaternion[0]), 0.0, 1.0)
        return log[:, A.e_norm], log[:, A.s_norm], log[:, A.clearance], 2 * np.arccos(cosine)

    def TaskMetrics(self, logs: Dict[str, np.ndarray]) -> Dict[str, float]:
        """The task's own metrics beside metrics.run_metrics' shared ones.

        Args:
            logs: The run's logs (RunResult.logs).

        Returns:
            Metric name -> value: the attitude error |e| (final, RMS and max after
                SETTLING_TIME) [rad], the smallest link-base distance [m] (nan without
                the potential, which measures it), the largest |spatial momentum| over
                the logged states and the share of samples with an actuator's command
                clipped to its effort limit."""
        layout = AttitudeLog()
        t, error = logs["time"], logs["attitude_log"][:, layout.e_norm]
        settled = t >= SETTLING_TIME
        clearance = logs["attitude_log"][:, layout.clearance]
        plant = self.truth_plant
        context = plant.CreateDefaultContext()
        momentum = 0.0
        for x in logs["state"]:
            plant.SetPositionsAndVelocities(context, x)
            momentum = max(momentum, float(np.max(np.abs(
                plant.CalcSpatialMomentumInWorldAboutPoint(context, np.zeros(3)
                                                           ).get_coeffs()))))
        nan = float("nan")
        return {
            "attitude_error_final": float(error[-1]) if len(error) else nan,
            "attitude_error_rms_settled": (float(np.sqrt(np.mean(error[settled]**2)))
                                           if settled.any() else nan),
            "attitude_error_max_settled": (float(np.max(error[settled]))
                                           if settled.any() else nan),
            "min_clearance": (float(np.min(clearance)) if np.all(np.isfinite(clearance))
                              and len(clearance) else nan),
            "max_momentum": momentum,
            # Samples where some actuator's command was clipped to its effort limit.
            "effort_saturated_share": (float(np.mean(np.any(logs["saturated"] > 0.5,
                                                            axis=1)))
                                       if "saturated" in logs and len(t) else nan)}

    def MeasuredMasses(self) -> Tuple[float, float]:
        """The ground truth's total and base mass, as a spacecraft's mass
        properties give them (the identifier's anchor, scenario.inertia).

        Returns:
            (total, base) [kg]."""
        base = KinematicTree.FromPlant(self.truth_plant).bodies[0]
        return self.TotalMass(), float(base.default_mass())

    def TotalMass(self) -> float:
        """The ground truth's total mass (its bodies with mass).

        Returns:
            The mass [kg]."""
        return float(sum(body.default_mass()
                         for body in InertialParameters(self.truth_plant).bodies))

    def VerifyLhs(self, logs: Dict[str, np.ndarray], region_budget: float
                  ) -> "LhsSide":
        """What dacph verify checks of this LHS.

        The LHS with K_d = damping_rate M and the inertia-scaled boundary layer
        (EnvelopeConstants.ForInertiaScaled), with the controller's model and, when
        it ran one, the inertial identifier's last estimate: the bounds of both.

        Args:
            logs: The run's logs (RunResult.logs).
            region_budget: The wall time [s] after which the region of
                attraction's program is stopped; the spatial certificate
                (region_of_attraction.moving_region_of_attraction) takes
                milliseconds, so it does not bind it.

        Returns:
            The analysis.verify.LhsSide."""
        from dacph_drake.analysis.lyapunov_envelope import EnvelopeConstants
        from dacph_drake.analysis.region_of_attraction import (
            moving_region_of_attraction)
        from dacph_drake.analysis.verify import LhsSide
        from dacph_drake.dynamics.inertia_bound import search_inertia_bound
        scenario, model = self.scenario, self.model
        models = [model]
        if "inertial_parameters" in logs:
            models.append(DescribedRobot(scenario).model)
            models[-1].SetInertialParameters(logs["inertial_parameters"][-1])
        n, gains = model.num_joints, scenario.task.gains
        lambda_min_M = min(search_inertia_bound(m).lambda_min for m in models)
        samples = np.random.default_rng(0).uniform(-np.pi, np.pi, (DIAGONAL_SAMPLES, n))
        max_diagonal_M = (1 + DIAGONAL_MARGIN) * max(
            float(np.max(np.diag(m.MassMatrix(q)))) for q in samples for m in models)
        L = AttitudeLog()
        return LhsSide(
            V=logs["attitude_log"][:, L.lyapunov_V],
            s0_norm=float(logs["attitude_log"][0, L.s_norm]),
            constants=EnvelopeConstants.ForInertiaScaled(
                gains.damping_rate, lambda_min_M, max_diagonal_M, gains.epsilon,
                gains.boundary_rate, n),
            lambda_lhs=2 * gains.damping_rate,
            region=moving_region_of_attraction(model, np.asarray(scenario.q0),
                                               gains.damping_rate),
            settings={"inf_lambda_min_M": lambda_min_M,
                      "sup_max_diagonal_M": max_diagonal_M})


def link_base_clearance(parsed: ParsedDescription, model: FloatingBaseModel,
                        query_distance: float = 1.0) -> Callable[[np.ndarray], float]:
    """The smallest signed distance between a link's collision geometry and the
    base's, as the clearance potential measures it (with its own contexts).

    Args:
        parsed: The arm's parsed description.
        model: Its model.
        query_distance: How far the distance is measured [m] (inf beyond).

    Returns:
        q -> the clearance [m]."""
    measure = BaseClearancePotential(parsed=parsed, model=model, gain=0.0,
                                     margin=query_distance, query_distance=query_distance)
    return lambda q: measure.Evaluate(q, _BASE_AT_REST).min_distance


def null_space_rate(parsed: ParsedDescription, model: FloatingBaseModel,
                    potential: ClearancePotential
                    ) -> Optional[Callable[[np.ndarray], float]]:
    """The clearance potential's null-space rate ||xi|| = eta ||grad U||.

    Args:
        parsed: The arm's parsed description.
        model: Its model.
        potential: The robot's potential settings (robot.potential).

    Returns:
        q -> ||xi|| [rad/s], or None with a zero gain or eta."""
    if potential.gain <= 0 or potential.eta <= 0:
        return None
    measure = BaseClearancePotential(parsed=parsed, model=model, gain=potential.gain,
                                     margin=potential.margin)
    return lambda q: potential.eta * float(np.linalg.norm(
        measure.Evaluate(q, _BASE_AT_REST).gradient))


def _RequireOneTree(trials) -> None:
    """ConfigError unless the trials' arms have one kinematic tree (the same
    joints on the same bodies: the batch's compiled kernels share it; their
    dimensions, axes and inertias may differ)."""
    first = KinematicTree.FromPlant(trials[0].parsed.plant)
    for i, trial in enumerate(trials[1:], start=1):
        tree = KinematicTree.FromPlant(trial.parsed.plant)
        if not all(np.array_equal(a, b) for a, b in (
                (tree.parent, first.parent), (tree.joint, first.joint),
                (tree.below, first.below))):
            raise ConfigError(f"trial {i}'s robot differs from trial 0's in its "
                              "kinematic tree; allowed: one arm for the trials of a "
                              "batch (its dimensions, axes and inertias may differ)")

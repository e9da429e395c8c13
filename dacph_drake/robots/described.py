"""An arm from a description file (scenario.DescribedArm: URDF/SDF/MJCF, the root body the
free base), parsed once per diagram into the truth's plant, which the controller's model
(FloatingBaseModel) evaluates in its own contexts, inertias scaled; its clearance."""
import copy
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from pydrake.geometry import Meshcat, SceneGraph
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import DiagramBuilder

from dacph_drake.dynamics.floating_model import FloatingBaseModel, arm_joints
from dacph_drake.dynamics.inertial_parameters import PER_BODY, InertialParameters
from dacph_drake.dynamics.kinematic_tree import KinematicTree
from dacph_drake.dynamics.plant import AddClonedArms
from dacph_drake.dynamics.sensor_noise import state_noise
from dacph_drake.scenario.errors import (ConfigError, require_finite_numbers, require_in_range,
                                require_nonnegative, require_one_of, require_positive)
from dacph_drake.robots.clearance_potential import BaseClearancePotential
from dacph_drake.robots.description import MakeRobotPlant, ParsedDescription
from dacph_drake.robots.robot import require_clear_start
from dacph_drake.robots.sizing import (MIN_AMPLITUDE, disturbance_scale, excitation_scale,
                                      potential_margin, scale_couplings,
                                      sized_disturbance, sized_uncertainty, truth_step)
from dacph_drake.robots.start_pose import (ATTITUDE_ROWS, POSITION_ROWS, choose_start,
                                           rehearse, task_jacobian, tracked)
from dacph_drake.scenario import (EFFORT_LIMITS, JOINT_DAMPING, JOINT_FRICTION,
                                  JOINT_LIMITS,
                                  ClearancePotential, DescribedArm, EndEffectorAttitude,
                                  Phases, Scenario)
from dacph_drake.scenario.built_in import (SATELLITE_PHASES, described_arm_learner,
                                           described_arm_periods, described_arm_rhs)
from dacph_drake.scenario.checks import require_length, validate_shared
from dacph_drake.scenario.simulator import FixedStepConfig
from dacph_drake.systems.inertial_identifier import InertialIdentifier
from dacph_drake.systems.spatial_true_rhs import SpatialTrueRhs


def validate_assembly(arm: DescribedArm) -> None:
    """Checks how the robot is put together, before it is parsed.

    Args:
        arm: The robot section.

    Raises:
        ConfigError: Naming the first invalid setting (base, mount, end effector, ...)."""
    require_one_of("robot.joint_damping", arm.joint_damping, JOINT_DAMPING)
    require_one_of("robot.joint_friction", arm.joint_friction, JOINT_FRICTION)
    require_one_of("robot.joint_limits", arm.joint_limits, JOINT_LIMITS)
    require_one_of("robot.effort_limits", arm.effort_limits, EFFORT_LIMITS)
    for name, position in arm.locked_joints.items():
        require_finite_numbers(f"robot.locked_joints.{name}", position)
    require_nonnegative("robot.base.mass", arm.base.mass, "kg")
    for name, values, count in (("base.size", arm.base.size, 3),
                                ("base.mount", arm.base.mount, 6),
                                ("end_effector.offset", arm.end_effector.offset, 3)):
        require_length(f"robot.{name}", values, count,
                        {3: "x, y, z", 6: "x, y, z, roll, pitch, yaw"}[count])
        require_finite_numbers(f"robot.{name}", list(values))
    for i, side in enumerate(arm.base.size):
        require_positive(f"robot.base.size[{i}]", side, "m")
    for i, folder in enumerate(arm.package_paths):
        if not Path(folder).is_dir():
            raise ConfigError(f"robot.package_paths[{i}] = {folder!r} is not a "
                              "folder; allowed: folders holding ROS packages "
                              "(package.xml)")
    for name, folder in arm.packages.items():
        if not Path(folder).is_dir():
            raise ConfigError(f"robot.packages.{name} = {folder!r} is not a folder; "
                              "allowed: the folder package://NAME/ stands for")

def validate_bodies(arm: DescribedArm, bodies: Sequence[str]) -> None:
    """Checks the settings that depend on the parsed description.

    Args:
        arm: The robot section.
        bodies: The names of the bodies with mass, in the plant's order.

    Raises:
        ConfigError: Naming the first invalid setting."""
    if len(arm.nominal_inertia_scale) not in (0, len(bodies)):
        raise ConfigError(f"robot.nominal_inertia_scale has "
                          f"{len(arm.nominal_inertia_scale)} entries; allowed: "
                          f"{len(bodies)}, one per body with mass in this order: "
                          f"{', '.join(bodies)}; or none")
    for i, f in enumerate(arm.nominal_inertia_scale):
        require_in_range(f"robot.nominal_inertia_scale[{i}]", f, 0.1, 10.0)
    require_nonnegative("robot.potential.gain", arm.potential.gain)
    require_positive("robot.potential.margin", arm.potential.margin, "m")
    require_nonnegative("robot.potential.eta", arm.potential.eta, "1/s")


def model_error_scale(arm: "DescribedArm", links: Optional[Sequence[float]],
                      base: Optional[float]) -> list:
    """robot.nominal_inertia_scale of a sweep's model error, per body with mass: ``base`` on
    the free base's, links[j] on joint j's child, 1 on others (a welded tool) or left out.

    Args:
        arm: The robot section (parsed once per process and section).
        links: One factor per joint, or None.
        base: The base body's factor, or None."""
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
    """(massive body names, the base's index, each joint child's index or None), cached."""
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


def joint_friction(parsed: ParsedDescription, model: FloatingBaseModel) -> np.ndarray:
    """The description's joint Coulomb friction f (n) [N m] in q's order (zero where none).

    Args:
        parsed: The parsed description.
        model: Its arm's model (the joints' order)."""
    return np.array([parsed.joint_friction.get(joint.name(), 0.0)
                     for joint in arm_joints(model)])


def require_every_joint_moves_inertia(model: FloatingBaseModel, description: str
                                      ) -> None:
    """Requires every actuated joint to move some inertia: else M_jj = 0, M(q) is singular
    and the gain rule's bound, the sizing's scales and the port's momentum are undefined.

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
    """robots.robot.Robot of a DescribedArm.

    Args:
        scenario: The scenario.
        task: The tasks.Task it serves.

    Raises:
        ConfigError: The first invalid setting, or what the description may not have."""

    # A sweep's trials per diagram (scripts/bench_sweep.py: little gain beyond 16); a
    # description has no link parameters to sample.
    BATCH_SIZE = 16
    TRUTH_SAMPLES: Tuple[str, ...] = ()

    @staticmethod
    def SizedScenario(section: DescribedArm, q0: Optional[Sequence[float]],
                      task: Optional[object], rows: Sequence[int]) -> Scenario:
        """robots.robot.Robot.SizedScenario: arm_scenario.

        Args:
            section: The file's robot section.
            q0: The file's q0 [rad] (None where it leaves it out).
            task: The file's task section (None where it leaves it out).
            rows: The GJM's rows that task tracks."""
        return arm_scenario(section, q0, task, rows)

    @staticmethod
    def ResolvePaths(section: DescribedArm, folder: Path) -> None:
        """robots.robot.Robot.ResolvePaths: the description, package_paths and packages
        (shipped names, package:// URIs, paths existing from the working directory stay).

        Args:
            section: The robot section (changed in place).
            folder: The scenario file's folder."""
        def resolved(path: str) -> str:
            beside = folder / path
            if Path(path).is_absolute() or (Path(path).exists() and not beside.exists()):
                return path
            return str(beside)
        if (not section.description.startswith("package://")
                and Path(section.description).suffix.lower() in (".urdf", ".sdf", ".xml")):
            section.description = resolved(section.description)
        section.package_paths = [resolved(path) for path in section.package_paths]
        section.packages = {name: resolved(path) for name, path in section.packages.items()}

    @staticmethod
    def JointNames(section: DescribedArm) -> List[str]:
        """robots.robot.Robot.JointNames: the description's joint names.

        Args:
            section: The robot section, its paths resolved."""
        return [joint.name() for joint in arm_joints(FloatingBaseModel(
            MakeRobotPlant(section)))]

    @staticmethod
    def ApplyTruthSample(section: DescribedArm, sampled: Dict[str, object]) -> None:
        """robots.robot.Robot.ApplyTruthSample: nothing to sample.

        Args:
            section: The robot section.
            sampled: The trial's sampled settings by name."""

    @staticmethod
    def ApplyModelError(section: DescribedArm, links: Optional[Sequence[float]],
                        base: Optional[float]) -> None:
        """robots.robot.Robot.ApplyModelError: on the joints' bodies (model_error_scale).

        Args:
            section: The robot section (changed in place).
            links: One factor per joint, or None.
            base: The base's factor, or None."""
        if links is not None or base is not None:
            section.nominal_inertia_scale = model_error_scale(section, links, base)

    def __init__(self, scenario: Scenario, task: "Task"):
        self.scenario, self.task = scenario, task
        arm = scenario.robot
        validate_assembly(arm)
        self.parsed = ParsedDescription(arm)
        self.model = FloatingBaseModel(self.parsed.plant)
        self.num_joints = self.model.num_joints
        require_every_joint_moves_inertia(self.model, arm.description)
        validate_bodies(arm, [body.name() for body in self.model.parameters.bodies])
        validate_shared(scenario, task, self.num_joints,
                        [joint.name() for joint in arm_joints(self.model)])
        if arm.nominal_inertia_scale:
            self.model.SetInertialParameters(self.model.inertial_parameters * np.repeat(
                arm.nominal_inertia_scale, PER_BODY))

    @property
    def joint_friction(self) -> np.ndarray:
        """joint_friction(), which the truth's RHS applies (robot.joint_friction "keep")."""
        return joint_friction(self.parsed, self.model)

    @property
    def truth_plant(self) -> MultibodyPlant:
        """The parsed plant, its default context holding the description's inertias."""
        return self.parsed.plant

    @classmethod
    def AddGroundTruth(cls, builder: DiagramBuilder, trials: Sequence["DescribedRobot"]
                       ) -> Tuple[MultibodyPlant, SceneGraph]:
        """The batch's truth and SceneGraph, (plant, scene_graph): one trial's parsed plant,
        or one plant of copies of each trial's arm (AddClonedArms), bit for bit the same.

        Args:
            builder: The closed loop's builder.
            trials: Each trial's Robot (one: a single run).

        Raises:
            ConfigError: The trials' arms differ in their kinematic tree."""
        if len(trials) == 1:
            return trials[0].parsed.AddTo(builder)
        _RequireOneTree(trials)
        return AddClonedArms(builder, [trial.parsed.plant for trial in trials])

    @classmethod
    def MakeTrueRhs(cls, plant: MultibodyPlant, trials: Sequence["DescribedRobot"]
                    ) -> SpatialTrueRhs:
        """Makes the port's true RHS of the trials' arms (spatial_true_rhs.SpatialTrueRhs).

        Args:
            plant: The trials' ground-truth plant (AddGroundTruth).
            trials: Each trial's Robot."""
        return SpatialTrueRhs(plant=plant, arms=[trial.parsed.plant for trial in trials],
                              uncertainties=[t.scenario.uncertainty for t in trials],
                              phases=[t.scenario.phases for t in trials],
                              frictions=[t.joint_friction for t in trials])

    def RequireRunnableStart(self) -> None:
        """Requires q0 within the joint limits ("stop"), links clear of the base, a truth
        step >= MIN_TRUTH_STEP (damping asking for less is named, not run for hours).

        Raises:
            ConfigError: The joint beyond its limits, the link in the base, or the step."""
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
        self.task.RequireRegularStart(self)
        require_clear_start(self.scenario.q0, self.Clearance())

    def LimitViolation(self) -> Optional[Callable[[np.ndarray], Optional[str]]]:
        """robots.robot.Robot.LimitViolation, with joint_limits "stop" and finite limits."""
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

    @classmethod
    def MakeInertialIdentifier(cls, trials: Sequence["DescribedRobot"]
                               ) -> InertialIdentifier:
        """The batch's InertialIdentifier, its prior the models' inertias.

        Args:
            trials: Each trial's Robot."""
        first = trials[0].scenario
        return InertialIdentifier(
            plants=[trial.model.plant for trial in trials],
            priors=[trial.model.inertial_parameters for trial in trials],
            settings=first.inertia, period=first.periods.learner_sample,
            error_period=first.periods.learner,
            seeds=[trial.scenario.seed for trial in trials],
            measured_masses=[trial.MeasuredMasses() for trial in trials],
            noise=state_noise(first.sensing, first.periods.rhs))

    def BasePotential(self) -> Optional[BaseClearancePotential]:
        """The link-base clearance potential of the model (None with a zero gain)."""
        arm = self.scenario.robot
        return (BaseClearancePotential(parsed=self.parsed, model=self.model,
                                       gain=arm.potential.gain, margin=arm.potential.margin)
                if arm.potential.gain > 0 else None)

    def Clearance(self) -> Optional[Callable[[np.ndarray], float]]:
        """robots.robot.Robot.Clearance: link_base_clearance, inf beyond CONTACT_QUERY."""
        return link_base_clearance(self.parsed, self.model, CONTACT_QUERY)

    def LiveView(self, loop: "ClosedLoop", meshcat: Meshcat) -> "viewers.LiveView":
        """A viewers.LiveView of the truth through a SpatialViewer, R_d(t) from the LHS.

        Args:
            loop: The closed loop (of this robot) being simulated.
            meshcat: The Meshcat to draw into."""
        from dacph_drake.robots.viewers import LiveView, SpatialViewer
        viewer = SpatialViewer(self.scenario.robot, meshcat)
        controller = loop.systems[self.task.lhs_name]
        return LiveView(loop.plant, meshcat, lambda root_context, x, t: viewer.Draw(
            x, controller.DesiredAttitude(t)[0]))

    def WriteAnimation(self, logs: Dict[str, np.ndarray], out_html: Union[str, Path]
                       ) -> Path:
        """Writes a run's HTML replay (viewers.write_spatial_animation); returns its path.

        Args:
            logs: The run's logs (RunResult.logs).
            out_html: The HTML file to write."""
        from dacph_drake.robots.viewers import write_spatial_animation
        return write_spatial_animation(self.scenario.robot, logs, out_html,
                                       log_name=self.task.log_name)

    def MeasuredMasses(self) -> Tuple[float, float]:
        """The truth's (total, base) mass [kg] as mass properties give them (the anchor)."""
        base = KinematicTree.FromPlant(self.truth_plant).bodies[0]
        return self.TotalMass(), float(base.default_mass())

    def TotalMass(self) -> float:
        """The ground truth's total mass [kg] (its bodies with mass)."""
        return float(sum(body.default_mass()
                         for body in InertialParameters(self.truth_plant).bodies))


def arm_scenario(robot: DescribedArm, q0: Optional[Sequence[float]] = None,
                 task: Optional[object] = None,
                 rows: Sequence[int] = ATTITUDE_ROWS) -> Scenario:
    """The scenario of an arm, sized to it (unsized where q0's length is wrong).

    Args:
        robot: The arm's robot section.
        q0: The initial joint angles [rad] (default: robots.start_pose.choose_start).
        task: The task it tracks (default EndEffectorAttitude()).
        rows: The GJM's rows the task tracks (Task.jacobian_rows; default the attitude's).

    Raises:
        ConfigError: Bad assembly settings, an unloadable description, no start found."""
    validate_assembly(robot)
    parsed = ParsedDescription(robot)
    model = FloatingBaseModel(parsed.plant)
    require_every_joint_moves_inertia(model, robot.description)
    task = EndEffectorAttitude() if task is None else task
    # The reference sizes the arm: its attitude's, or (a position task) its position's.
    reference = getattr(task, "reference", None) or task.position
    rehearsal_time = SATELLITE_PHASES["warmup"] + reference.period
    clearance = link_base_clearance(parsed, model)     # one SceneGraph context
    if q0 is None:
        try:
            q0 = choose_start(model, task, clearance,
                              null_space_rate(parsed, model, robot.potential),
                              rehearsal_time, rows)
        except ValueError as e:
            what = tracked(rows)
            how = {"attitude": "turn about every axis",
                   "position": "move in every direction"}.get(
                what, "turn about every axis and move in every direction")
            raise ConfigError(
                f"robot.description {robot.description!r}: no start pose found for "
                f"the end-effector {what} task ({e}); allowed: a q0 in the file, or "
                f"an arm whose end effector can {how}") from e
    q0 = np.asarray(q0, float)
    robot = copy.deepcopy(robot)
    if len(q0) == model.num_joints:
        robot.potential.margin = potential_margin(robot.potential.margin,
                                                  clearance(q0))
    scenario = Scenario(robot=robot, task=task, q0=[float(x) for x in q0],
                        phases=Phases(**SATELLITE_PHASES), rhs=described_arm_rhs(),
                        periods=described_arm_periods(), learner=described_arm_learner())
    if len(q0) != model.num_joints:
        return scenario         # Validate names q0's length; nothing to size by
    rate = 2 * np.pi * max(_reference_angle(model, q0, task), MIN_AMPLITUDE) \
        / reference.period
    M = model.MassMatrix(q0)
    inertia = np.diag(M)
    rehearsal = rehearse(model, q0, task, rehearsal_time)
    # Past the warm-up: the uncertainty and the disturbance act from phase 1 on, when
    # the start's error has decayed (the rehearsal also starts with a jump in p).
    steady = rehearsal.time >= SATELLITE_PHASES["warmup"]
    momentum = np.maximum(inertia * rate, np.max(np.abs(rehearsal.p[steady]), axis=0))
    torque = np.maximum(inertia * rate * 2 * np.pi / reference.period,
                        np.max(np.abs(rehearsal.p_rate[steady]), axis=0))
    scenario.uncertainty = sized_uncertainty(inertia, momentum)
    # The paper's q1^2 coupling at the angles the task reaches: at most its size at
    # |q1| = 1 rad (the paper's arm stays within it). From a start at q1 = 2.9 rad
    # (a UR5's chosen start) it would put 3.5 of joint 1's command into joint 2's
    # torque, and the true RHS loop lost its margin (spectral radius 0.97 > 0.95).
    reach = float(np.max(rehearsal.q[steady, 0] ** 2))
    if reach > 1.0:
        scenario.uncertainty.B_q1_squared = (
            np.asarray(scenario.uncertainty.B_q1_squared) / reach).tolist()
    scale_couplings(scenario.uncertainty, torque)
    scenario.disturbance = sized_disturbance(torque)
    scenario.disturbance.scale = disturbance_scale(
        scenario.disturbance, M, rate * 2 * np.pi / reference.period)
    scenario.excitation.joint_scale = excitation_scale(scenario.excitation, M)
    scenario.simulator = FixedStepConfig(step=truth_step(
        model, rehearsal.q, scenario.uncertainty, scenario.periods.rhs,
        joint_friction(parsed, model)))
    return scenario


def _reference_angle(model: "FloatingBaseModel", q0: np.ndarray, task) -> float:
    """The reference's amplitude as a joint angle [rad]: the attitude's, or a position's [m]
    over the position rows' largest singular value at q0 [m/rad] (the longest lever)."""
    if getattr(task, "reference", None) is not None:
        return task.reference.amplitude
    lever = np.linalg.svd(task_jacobian(model, q0, rows=POSITION_ROWS),
                          compute_uv=False)[0]
    return task.position.amplitude / max(lever, 1e-9)


def link_base_clearance(parsed: ParsedDescription, model: FloatingBaseModel,
                        query_distance: float = 1.0) -> Callable[[np.ndarray], float]:
    """q -> the smallest link-base signed distance [m], as the clearance potential's.

    Args:
        parsed: The arm's parsed description.
        model: Its model.
        query_distance: How far the distance is measured [m] (inf beyond)."""
    measure = BaseClearancePotential(parsed=parsed, model=model, gain=0.0,
                                     margin=query_distance, query_distance=query_distance)
    return lambda q: measure.Evaluate(q, _BASE_AT_REST).min_distance


def null_space_rate(parsed: ParsedDescription, model: FloatingBaseModel,
                    potential: ClearancePotential
                    ) -> Optional[Callable[[np.ndarray], float]]:
    """q -> the null-space rate ||xi|| = eta ||grad U|| [rad/s]; None with gain or eta 0.

    Args:
        parsed: The arm's parsed description.
        model: Its model.
        potential: The robot's potential settings (robot.potential)."""
    if potential.gain <= 0 or potential.eta <= 0:
        return None
    measure = BaseClearancePotential(parsed=parsed, model=model, gain=potential.gain,
                                     margin=potential.margin)
    return lambda q: potential.eta * float(np.linalg.norm(
        measure.Evaluate(q, _BASE_AT_REST).gradient))


def _RequireOneTree(trials) -> None:
    """ConfigError unless the trials' arms share one kinematic tree, as the kernels do."""
    first = KinematicTree.FromPlant(trials[0].parsed.plant)
    for i, trial in enumerate(trials[1:], start=1):
        tree = KinematicTree.FromPlant(trial.parsed.plant)
        if not all(np.array_equal(a, b) for a, b in (
                (tree.parent, first.parent), (tree.joint, first.joint),
                (tree.below, first.below))):
            raise ConfigError(f"trial {i}'s robot differs from trial 0's in its "
                              "kinematic tree; allowed: one arm for the trials of a "
                              "batch (its dimensions, axes and inertias may differ)")

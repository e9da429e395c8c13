"""The sweep file: a base scenario, the distributions to sample (``pydrake.common.schema``),
the number of trials, the controllers run on each sample; and the sampling of one trial
from (sweep seed, trial id) only.

Every sampled setting is optional (absent: the base's value). ``*_scale`` multiplies the
base's value; ``q0`` and ``learner_seed`` replace it. Per-link settings take a vector
distribution (one entry per link) or a scalar one (drawn independently per link).
``nominal_*`` perturb the controllers' model; ``fault_*`` add one actuator fault;
``link_*`` and ``base_*`` apply where the robot takes them (Robot.TRUTH_SAMPLES). A
sample failing ``Scenario.Validate()`` is a failed trial with the ConfigError's message."""
import copy
import hashlib
from dataclasses import dataclass, field, fields, is_dataclass
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Union

import numpy as np
from pydrake.common import RandomGenerator, schema
from pydrake.common.yaml import yaml_dump_typed, yaml_load

from dacph_drake.assembly.registry import robot_kind
from dacph_drake.controllers import NAMES as CONTROLLERS
from dacph_drake.scenario.errors import ConfigError, require_in_range
from dacph_drake.scenario.yaml_files import load_yaml_dataclass, read_yaml
from dacph_drake.scenario import Scenario
from dacph_drake.scenario.built_in import BUILT_IN_SCENARIOS
from dacph_drake.assembly.scenario_files import load_scenario, saved_forms

# The ground-truth robot's distributions (planar arms only).
ROBOT_DISTRIBUTIONS = ("link_mass_scale", "link_length_scale", "link_inertia_scale",
                       "base_mass_scale", "base_inertia_scale")


# The YAML tags of Drake's distributions, and DistributionVariant and
# DistributionVectorVariantX as Python unions (plus a scalar distribution drawn per
# entry in the vector case).
SCALAR_TAGS = {"Deterministic": schema.Deterministic, "Gaussian": schema.Gaussian,
               "Uniform": schema.Uniform, "UniformDiscrete": schema.UniformDiscrete}
VECTOR_TAGS = {"DeterministicVector": schema.DeterministicVectorX,
               "GaussianVector": schema.GaussianVectorX,
               "UniformVector": schema.UniformVectorX}
ScalarDistribution = Union[(float, *SCALAR_TAGS.values())]
VectorDistribution = Union[(List[float], *VECTOR_TAGS.values(), float,
                            *SCALAR_TAGS.values())]


@dataclass
class Distributions:
    """What each trial samples (module docstring); None keeps the base scenario's value.

    Attributes:
        link_mass_scale: The ground truth's link mass and inertia, per link (planar arms).
        link_length_scale: Its link length, com and width by f, inertia by f^2 (planar).
        link_inertia_scale: The ground truth's link inertia only, per link (planar arms).
        base_mass_scale: The ground truth's base mass and inertia (planar arms only).
        base_inertia_scale: The ground truth's base inertia only (planar arms only).
        delta_B_scale: The ground truth's B_linear, B_quadratic and B_q1_squared.
        delta_D_scale: The ground truth's D_offset, D_linear and D_quadratic.
        disturbance_scale: d(t)'s amplitude (disturbance.scale).
        disturbance_frequency_scale: All of d's frequencies.
        q0: The initial joint angles [rad], one per joint (replaces q0).
        learner_seed: The scenario's seed, integers >= 0 (None: the trial's, trial_seed).
        nominal_link_mass_scale: nominal_robot's link mass and inertia, per link (a
            described arm: robot.nominal_inertia_scale).
        nominal_base_mass_scale: The controller's model error on the base mass and inertia.
        actuator_gain_log10: x_j per joint: B~'s row j times 10^x_j (uncertainty.B_scale).
        fault_time: From it [s], fault_joint gives fault_gain times its torque (all/none).
        fault_joint: The fault's joint (1-based, rounded to an integer).
        fault_gain: The fault's factor on the joint's torque.
        sensing_noise_scale: Every noise of the base's sensing section (the encoders',
            tachometers', gyro's noise, bias and bias walk, the star tracker's) times f
            (the sensing samples need the base's sensing.enabled; trials with equal
            ones share a batch's diagram).
        sensing_rhs_delay: sensing.rhs_delay [samples] (rounded to an integer).
        sensing_actuator_lag: sensing.actuator_lag [s]."""
    # Ground-truth robot (the controllers keep nominal_robot), one factor per link:
    link_mass_scale: Optional[VectorDistribution] = None     # mass and inertia
    link_length_scale: Optional[VectorDistribution] = None   # length, com, width by f,
    #                                                          inertia by f^2
    link_inertia_scale: Optional[VectorDistribution] = None  # inertia only
    base_mass_scale: Optional[ScalarDistribution] = None     # base mass and inertia
    base_inertia_scale: Optional[ScalarDistribution] = None  # base inertia only
    # Ground-truth RHS:
    delta_B_scale: Optional[ScalarDistribution] = None  # B_linear, B_quadratic, B_q1_squared
    delta_D_scale: Optional[ScalarDistribution] = None  # D_offset, D_linear, D_quadratic
    disturbance_scale: Optional[ScalarDistribution] = None     # d(t) amplitude
    disturbance_frequency_scale: Optional[ScalarDistribution] = None  # all of d's
    #                                                                  frequencies
    q0: Optional[VectorDistribution] = None             # initial joint angles [rad]
    learner_seed: Optional[ScalarDistribution] = None   # integers; None: the trial's
    #                                                     own seed (see trial_seed)
    # The controller's model error (the ground truth keeps its robot): one factor per
    # link on nominal_robot's link mass and inertia, one on its base's (a described
    # arm: the body each joint moves, in robot.nominal_inertia_scale).
    nominal_link_mass_scale: Optional[VectorDistribution] = None
    nominal_base_mass_scale: Optional[ScalarDistribution] = None
    # Actuators: B~'s row j times 10^x_j (uncertainty.B_scale), and one fault: from
    # fault_time [s] on, joint fault_joint (1-based) delivers fault_gain times its
    # torque (uncertainty.faults; the three go together).
    actuator_gain_log10: Optional[VectorDistribution] = None
    fault_time: Optional[ScalarDistribution] = None
    fault_joint: Optional[ScalarDistribution] = None
    fault_gain: Optional[ScalarDistribution] = None
    # Sensing (the base's sensing section, enabled): its noises times f, its command
    # delay and actuator lag replaced.
    sensing_noise_scale: Optional[ScalarDistribution] = None
    sensing_rhs_delay: Optional[ScalarDistribution] = None
    sensing_actuator_lag: Optional[ScalarDistribution] = None


# The sensing section's noises (Distributions.sensing_noise_scale).
SENSING_NOISES = ("encoder_noise", "rate_noise", "gyro_noise", "gyro_bias",
                  "gyro_bias_walk", "star_tracker_noise")


@dataclass
class Sweep:
    """A sweep file's settings.

    Attributes:
        scenario: A BUILT_IN_SCENARIOS name or a YAML path relative to the sweep file.
        trials: The number of trials, in [1, 10^6].
        seed: The sweep's seed, an integer in [0, 2^32 - 1] (trial_seed).
        controllers: The controllers run on each sample (controllers.NAMES, each once).
        distributions: What each trial samples (Distributions).
        save_logs: Whether each run's logs are also written under OUT/logs/.
        batch_size: Trials per diagram in [0, 4096] (0: runner.batch_size_for).
        verify: Whether each run with the RHS integrator is also verified (dacph
            verify's checks, the region of attraction skipped): its row's ``verify``."""
    scenario: str = "short"     # built-in name (paper, short) or YAML path, relative
    #                             to the sweep file
    trials: int = 10
    seed: int = 0
    controllers: List[str] = field(default_factory=lambda: list(CONTROLLERS))
    distributions: Distributions = field(default_factory=Distributions)
    save_logs: bool = False     # also write each run's logs under OUT/logs/
    batch_size: int = 0         # trials per diagram (runner.batch_size_for; 0: chosen
    #                             by measurement); no trial's row depends on it
    verify: bool = False


@dataclass
class SweepDefinition:
    """A loaded, validated sweep with its base scenario.

    Attributes:
        sweep: The sweep file's settings.
        scenario: The base scenario.
        source: The sweep file.
        text: The sweep file as written."""
    sweep: Sweep
    scenario: Scenario          # the base scenario
    source: Path                # the sweep file
    text: str                   # the sweep file as written

    def fingerprint(self) -> str:
        """sha256 hex digest of the normalized sweep and scenario (same: same trials)."""
        return self.fingerprints()[0]

    def fingerprints(self) -> List[str]:
        """fingerprint() and the older scenario layouts' (batch_size not included, nor
        verify at its default, which came after)."""
        sweep = "".join(line for line in yaml_dump_typed(self.sweep).splitlines(True)
                        if not line.startswith("batch_size:")
                        and line != "verify: false\n")
        return [hashlib.sha256((sweep + "\n---\n" + form).encode()).hexdigest()
                for form in saved_forms(self.scenario)]


@dataclass
class TrialSample:
    """One trial's sample.

    Attributes:
        trial: The trial id.
        seed: The trial's seed (trial_seed).
        scenario: The base scenario with the sample applied.
        sampled: Setting -> its sampled value (a float, a list of floats, or an int)."""
    trial: int
    seed: int
    scenario: Scenario               # the base scenario with the sample applied
    sampled: Dict[str, object]       # setting -> float, list of floats, or int


def load_sweep(path: Union[str, Path]) -> SweepDefinition:
    """Loads and validates a sweep file and its base scenario.

    Args:
        path: The sweep file.

    Raises:
        ConfigError: Naming the invalid setting and what is allowed."""
    path = Path(path)
    read_yaml(path)         # a file that cannot be read or parsed, named (one line)
    try:
        raw = yaml_load(filename=str(path))
    except (OSError, RuntimeError, ValueError) as e:
        raise ConfigError(f"{path}: {e}") from e
    _check_keys(raw, Sweep, f"{path}: ")
    _check_distribution_keys((raw or {}).get("distributions") or {}, f"{path}: ")
    sweep = load_yaml_dataclass(path, Sweep)
    require_in_range("trials", sweep.trials, 1, 10**6)
    require_in_range("seed", sweep.seed, 0, 2**32 - 1)
    require_in_range("batch_size", sweep.batch_size, 0, 4096)
    if not sweep.controllers:
        raise ConfigError(f"controllers is empty; allowed: one or more of "
                          f"{', '.join(CONTROLLERS)}")
    for name in sweep.controllers:
        if name not in CONTROLLERS:
            raise ConfigError(f"controllers: {name!r} is unknown; allowed: "
                              f"{', '.join(CONTROLLERS)}")
    if len(set(sweep.controllers)) != len(sweep.controllers):
        raise ConfigError(f"controllers = {sweep.controllers} names one twice; allowed: "
                          "each at most once")
    scenario = _base_scenario(sweep.scenario, path.parent)
    for name in ROBOT_DISTRIBUTIONS:
        if (getattr(sweep.distributions, name) is not None
                and name not in robot_kind(scenario.robot).TRUTH_SAMPLES):
            raise ConfigError(
                f"distributions.{name} with the scenario {sweep.scenario!r}, whose robot "
                f"is a {type(scenario.robot).__name__}; allowed: the settings other "
                f"than {', '.join(ROBOT_DISTRIBUTIONS)} (its robot has no such "
                "parameters)")
    _check_distributions(sweep.distributions, len(scenario.q0))
    sensing = [f.name for f in fields(Distributions) if f.name.startswith("sensing_")
               and getattr(sweep.distributions, f.name) is not None]
    if sensing and not scenario.sensing.enabled:
        raise ConfigError(f"distributions.{sensing[0]} samples the base scenario's "
                          "sensing, which is off; allowed: a base scenario with "
                          "sensing.enabled: true")
    return SweepDefinition(sweep=sweep, scenario=scenario, source=path,
                           text=path.read_text())


def _base_scenario(name: str, folder: Path) -> Scenario:
    """A built-in scenario, or a scenario file relative to the sweep file."""
    if name in BUILT_IN_SCENARIOS:
        return BUILT_IN_SCENARIOS[name]()
    path = folder / name
    if not path.is_file():
        raise ConfigError(f"scenario = {name!r} is neither a built-in scenario nor a file "
                          f"(looked for {path}); allowed: {', '.join(BUILT_IN_SCENARIOS)} "
                          "or a scenario YAML path relative to the sweep file")
    return load_scenario(path)


def _check_keys(data, schema_type, where: str) -> None:
    """Unknown keys, named with the allowed ones."""
    if not isinstance(data, dict):
        return
    allowed = {f.name: f.type for f in fields(schema_type)}
    for key, value in data.items():
        if key == "_tag":
            continue
        if key not in allowed:
            raise ConfigError(f"{where}unknown key {key!r}; allowed: {', '.join(allowed)}")
        if is_dataclass(allowed[key]):
            _check_keys(value, allowed[key], f"{where}{key}.")


def _check_distribution_keys(raw: dict, where: str) -> None:
    """Each distribution's tag and keys, named with the allowed ones."""
    per_link = {f.name for f in fields(Distributions) if _is_per_link(f)}
    for name, value in raw.items():
        if not isinstance(value, dict):
            continue
        tags = {**SCALAR_TAGS, **VECTOR_TAGS} if name in per_link else SCALAR_TAGS
        tag = value.get("_tag", "!")[1:]
        if tag not in tags:
            raise ConfigError(f"{where}distributions.{name}: !{tag} is not a distribution "
                              f"here; allowed: {', '.join('!' + t for t in tags)}")
        allowed = [f.name for f in tags[tag].__fields__]
        for key in value:
            if key != "_tag" and key not in allowed:
                raise ConfigError(f"{where}distributions.{name}: unknown key {key!r} of "
                                  f"!{tag}; allowed: {', '.join(allowed)}")


def _check_distributions(d: Distributions, num_links: int) -> None:
    for f in fields(Distributions):
        value = getattr(d, f.name)
        if value is None:
            continue
        name = f"distributions.{f.name}"
        if _is_per_link(f):
            _check_vector(name, value, num_links)
        else:
            _check_scalar(name, value)
    if d.learner_seed is not None:
        _check_seed_values(d.learner_seed)
    fault = [d.fault_time is not None, d.fault_joint is not None, d.fault_gain is not None]
    if any(fault) and not all(fault):
        raise ConfigError("distributions.fault_time, fault_joint and fault_gain go "
                          "together; allowed: all three or none")


def _is_per_link(setting) -> bool:
    """Whether a Distributions field takes one value per link (or joint)."""
    return setting.type == Optional[VectorDistribution]


def _check_scalar(name: str, value) -> None:
    if isinstance(value, schema.Gaussian) and not value.stddev >= 0:
        raise ConfigError(f"{name}: !Gaussian stddev = {value.stddev}; allowed: >= 0")
    if isinstance(value, schema.Uniform) and not value.min <= value.max:
        raise ConfigError(f"{name}: !Uniform min = {value.min} > max = {value.max}; "
                          "allowed: min <= max")
    if isinstance(value, schema.UniformDiscrete) and len(value.values) == 0:
        raise ConfigError(f"{name}: !UniformDiscrete values is empty; allowed: one or "
                          "more values")
    for number in _numbers_of(value):
        if not np.isfinite(number):
            raise ConfigError(f"{name} = {number}; allowed: finite numbers")


def _check_vector(name: str, value, n: int) -> None:
    if isinstance(value, list):
        sizes = {"entries": len(value)}
    elif isinstance(value, schema.DeterministicVectorX):
        sizes = {"value": len(value.value)}
    elif isinstance(value, schema.GaussianVectorX):
        sizes = {"mean": len(value.mean)}
        if len(value.stddev) not in (1, n):
            raise ConfigError(f"{name}: !GaussianVector stddev has {len(value.stddev)} "
                              f"entries; allowed: 1 or {n} (one per link)")
        if not np.all(np.asarray(value.stddev) >= 0):
            raise ConfigError(f"{name}: !GaussianVector stddev = {list(value.stddev)}; "
                              "allowed: >= 0")
    elif isinstance(value, schema.UniformVectorX):
        sizes = {"min": len(value.min), "max": len(value.max)}
        if sizes["min"] == sizes["max"] and not np.all(value.min <= value.max):
            raise ConfigError(f"{name}: !UniformVector min = {list(value.min)} exceeds "
                              f"max = {list(value.max)}; allowed: min <= max entrywise")
    else:
        _check_scalar(name, value)
        return
    for part, size in sizes.items():
        if size != n:
            raise ConfigError(f"{name}: {part} has {size} entries; allowed: {n} "
                              "(one per link)")
    for number in _numbers_of(value):
        if not np.isfinite(number):
            raise ConfigError(f"{name} = {number}; allowed: finite numbers")


def _check_seed_values(value) -> None:
    if isinstance(value, (schema.Gaussian, schema.Uniform)):
        raise ConfigError("distributions.learner_seed: a continuous distribution; "
                          "allowed: an integer, !Deterministic or !UniformDiscrete of "
                          "integers >= 0")
    for number in _numbers_of(value):
        if not (number >= 0 and float(number).is_integer()):
            raise ConfigError(f"distributions.learner_seed = {number}; allowed: "
                              "integers >= 0")


def _numbers_of(value) -> List[float]:
    """The numbers written in a distribution's fields."""
    if isinstance(value, (int, float)):
        return [float(value)]
    if isinstance(value, list):
        return [float(v) for v in value]
    numbers = []
    for f in type(value).__fields__:
        numbers.extend(np.atleast_1d(np.asarray(getattr(value, f.name), float)).tolist())
    return numbers


def trial_seed(sweep_seed: int, trial: int) -> int:
    """A trial's seed in [0, 2^32 - 1] from (sweep seed, trial id) only (SeedSequence):
    of the sample and, unless learner_seed is sampled, of the learner and the noise.

    Args:
        sweep_seed: The sweep's seed.
        trial: The trial id."""
    return int(np.random.SeedSequence([sweep_seed, trial]).generate_state(1)[0])


def sample_trial(definition: SweepDefinition, trial: int) -> TrialSample:
    """One trial's scenario, sampled in Distributions' order from trial_seed's generator.

    Args:
        definition: The sweep.
        trial: The trial id."""
    seed = trial_seed(definition.sweep.seed, trial)
    generator = RandomGenerator(seed)
    d = definition.sweep.distributions
    n = len(definition.scenario.q0)
    sampled: Dict[str, object] = {}
    for f in fields(Distributions):
        value = getattr(d, f.name)
        if value is None:
            continue
        if _is_per_link(f):
            sampled[f.name] = _sample_vector(value, n, generator)
        else:
            sampled[f.name] = float(schema.ToDistribution(value).Sample(generator))
    for name in ("learner_seed", "fault_joint", "sensing_rhs_delay"):
        if name in sampled:
            sampled[name] = int(round(sampled[name]))
    scenario = apply_sample(definition.scenario, sampled, seed)
    return TrialSample(trial=trial, seed=seed, scenario=scenario, sampled=sampled)


def _sample_vector(value, n: int, generator: RandomGenerator) -> List[float]:
    if isinstance(value, list):
        return [float(v) for v in value]
    if isinstance(value, (schema.DeterministicVectorX, schema.GaussianVectorX,
                          schema.UniformVectorX)):
        return [float(v) for v in schema.ToDistributionVector(value).Sample(generator)]
    distribution = schema.ToDistribution(value)
    return [float(distribution.Sample(generator)) for _ in range(n)]


def apply_model_error_sample(robot: object, links: Optional[Sequence[float]],
                             base: Optional[float]) -> None:
    """Applies a trial's controller model error (Robot.ApplyModelError).

    Args:
        robot: The robot section.
        links: One factor per link (joint), or None.
        base: The base's factor, or None."""
    robot_kind(robot).ApplyModelError(robot, links, base)


def apply_sample(base: Scenario, sampled: Dict[str, object], seed: int) -> Scenario:
    """A copy of a scenario with sampled settings applied (module docstring).

    Args:
        base: The base scenario (left as it is).
        sampled: Setting -> its sampled value (TrialSample.sampled).
        seed: The trial's seed: scenario.seed = learner_seed if sampled, else ``seed``."""
    s = copy.deepcopy(base)
    robot_kind(s.robot).ApplyTruthSample(s.robot, sampled)
    u = s.uncertainty
    fB, fD = sampled.get("delta_B_scale", 1.0), sampled.get("delta_D_scale", 1.0)
    u.B_linear = [[fB * v for v in row] for row in u.B_linear]
    u.B_q1_squared = [[fB * v for v in row] for row in u.B_q1_squared]
    u.B_quadratic = [fB * v for v in u.B_quadratic]
    u.D_offset = [fD * v for v in u.D_offset]
    u.D_linear = [fD * v for v in u.D_linear]
    u.D_quadratic = [fD * v for v in u.D_quadratic]
    dist = s.disturbance
    dist.scale *= sampled.get("disturbance_scale", 1.0)
    f = sampled.get("disturbance_frequency_scale", 1.0)
    dist.lf_frequency = [f * v for v in dist.lf_frequency]
    dist.hf_frequency *= f
    if "q0" in sampled:
        s.q0 = list(sampled["q0"])
    s.seed = sampled.get("learner_seed", seed)
    _apply_model_error_sample(s, sampled)
    _apply_sensing_sample(s.sensing, sampled)
    return s


def _apply_sensing_sample(sensing, sampled: Dict[str, object]) -> None:
    """The sensing section's sampled noise scale, command delay and actuator lag."""
    if "sensing_noise_scale" in sampled:
        for name in SENSING_NOISES:
            setattr(sensing, name, sampled["sensing_noise_scale"] * getattr(sensing, name))
    if "sensing_rhs_delay" in sampled:
        sensing.rhs_delay = sampled["sensing_rhs_delay"]
    if "sensing_actuator_lag" in sampled:
        sensing.actuator_lag = sampled["sensing_actuator_lag"]


def _apply_model_error_sample(s, sampled: Dict[str, object]) -> None:
    """The controller's model error and the actuators' sampled settings."""
    from dacph_drake.scenario import ActuatorFault
    apply_model_error_sample(s.robot, sampled.get("nominal_link_mass_scale"),
                             sampled.get("nominal_base_mass_scale"))
    if "actuator_gain_log10" in sampled:
        s.uncertainty.B_scale = [10.0**x for x in sampled["actuator_gain_log10"]]
    if "fault_time" in sampled:
        s.uncertainty.faults = list(s.uncertainty.faults) + [ActuatorFault(
            time=sampled["fault_time"], joint=int(round(sampled["fault_joint"])),
            gain=sampled["fault_gain"])]

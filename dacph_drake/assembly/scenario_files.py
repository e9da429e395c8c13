"""Scenario files: load, save, saved_forms (a saved run's fingerprinted texts) and the older
layouts (PlanarLayoutV1, SpatialLayoutV1), so old files load and runs keep fingerprints."""
import dataclasses
import difflib
import logging
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Dict, List, Optional, Tuple, Union

from pydrake.common.yaml import yaml_dump_typed
from pydrake.systems.analysis import SimulatorConfig

from dacph_drake.scenario.errors import ConfigError
from dacph_drake.scenario.planar_arm import RobotParams
from dacph_drake.scenario.yaml_files import load_yaml_dataclass, read_yaml
from dacph_drake.scenario import (AttitudeGains, AttitudeReference, ClearancePotential,
                                  DescribedArm, Disturbance, EndEffectorAngle,
                                  EndEffectorAttitude, Excitation,
                                  InertiaIdentification, Learner, LocalBayes, LhsGains,
                                  Periods, Phases, PlanarArm, Potential, Reference,
                                  Rhs, Scenario, Sensing, Stress, Uncertainty)
from dacph_drake.scenario.built_in import (BUILT_IN_SCENARIOS, described_arm_learner,
                                           described_arm_rhs, six_dof_disturbance,
                                           six_dof_uncertainty)
from dacph_drake.scenario.simulator import FixedStepConfig
from dacph_drake.assembly.registry import robot_kind, sized_defaults, validate_scenario

# The YAML lines of settings added after planar runs were first saved, at their
# defaults, and the sections added since: left out of PlanarLayoutV1's saved forms
# where they hold their defaults, so that runs saved before they existed match.
ADDED_SETTING_DEFAULTS = ("  coupling: uniform", "  prior_scale: pooled",
                          "  B_scale: []", "  faults: []", "  trust_anchor: in_use",
                          "  start_hold: 1.0", "  gain_rule: paper",
                          "  evidence_ratio: 0.5", "  evidence_window: 1.0",
                          "  min_window: 0.5", "  warm_start: true",
                          "  model_change: true", "  step_guard: 10.0",
                          "  boundary_rate: 0.0", "  model: local_bayes",
                          "  adoption: certified_set", "  fit_tolerance: 1.0e-05",
                          "  anchor: total_mass")
# Settings added to the current layout since it was introduced: (section, key, the
# value that reproduces the behaviour before it). An input file that does not name
# one runs it at its current default, like any setting; a saved run's scenario.yaml
# (load_saved_scenario) that lacks it was written before it and is read with that
# value, the run's meaning. The key's line at that value is left out of the
# fingerprinted text, so a run saved before it keeps its fingerprint (saved_forms).
ADDED_TO_CURRENT_LAYOUT = (("learner", "prior_fallback", False),
                           ("learner", "model", "network"),
                           ("rhs", "adoption", "trust_band"),
                           ("inertia", "anchor", "model"),
                           ("inertia", "anchor_mass", 0.0),
                           ("inertia", "anchor_error", 0.0),
                           ("inertia", "fit_tolerance", 0.0),
                           ("inertia", "on_mismatch", "identified"),
                           ("excitation", "joint_scale", []),
                           ("inertia", "nominal_tolerance", 0.1),
                           ("inertia", "anchor_tolerance", 0.01),
                           ("inertia", "kinematic_tolerance", 0.0),
                           ("inertia", "error_draws", 16))
# Settings added since whose default is the behaviour before them, so neither an input
# file nor a saved run needs a value for them: only their line at that default is left
# out of the fingerprinted text ((section class, key, default); a robot kind's own
# settings, and those of sections added after the current layout).
ADDED_AT_THE_OLD_BEHAVIOUR = (("DescribedArm", "joint_friction", "zero"),
                              ("Sensing", "unmodelled_delay", 0))


def _bayes_as_introduced() -> LocalBayes:
    """learner.bayes with its defaults as introduced (a frozen record, never edited)."""
    return LocalBayes(model_error=0.1, min_dof=6.0)


# Sections added to the current layout's sections since it was introduced, with their
# settings as introduced: their lines at those values are left out of the
# fingerprinted text too, and a saved run's file without them reads them at those
# values (an input file, at today's defaults).
ADDED_SUBSECTIONS = (("learner", "bayes", _bayes_as_introduced),)


def _sensing_as_introduced() -> Sensing:
    """sensing: as introduced, off (a frozen record, never edited)."""
    return Sensing(enabled=False, encoder_counts=0, encoder_noise=0.0,
                   rate_source="tachometer", rate_noise=0.0, rate_cutoff=200.0,
                   gyro_noise=0.0, gyro_bias=0.0, gyro_bias_walk=0.0,
                   star_tracker_noise=0.0, star_tracker_rate=0.0, latency=0, lhs_delay=0,
                   rhs_delay=0, actuator_lag=0.0)


# Top-level sections added since, at the behaviour before them: the section's text
# as introduced is left out of the fingerprinted text (a later change of its defaults
# leaves runs saved before it their fingerprints).
ADDED_SECTIONS = (("sensing", _sensing_as_introduced),)


def _without_default_sections(text: str) -> str:
    """The YAML text without each ADDED_SECTIONS section that holds its values as
    introduced."""
    for name, introduced in ADDED_SECTIONS:
        block = "".join(f"  {line}\n" for line in
                        yaml_dump_typed(introduced()).splitlines())
        text = text.replace(f"{name}:\n{block}", "")
    return text


def as_before_added(scenario: Scenario) -> Scenario:
    """``scenario`` with the settings and sections added since as they were before.

    Args:
        scenario: The scenario."""
    import copy
    before = copy.deepcopy(scenario)
    for section, key, value in ADDED_TO_CURRENT_LAYOUT:
        setattr(getattr(before, section), key, value)
    for section, key, defaults in ADDED_SUBSECTIONS:
        setattr(getattr(before, section), key, defaults())
    return before


def _added_lines() -> Tuple[str, ...]:
    """The added settings' and ADDED_SUBSECTIONS' lines, as yaml_dump_typed writes them."""
    lines = [f"  {key}: {str(value).lower()}" for _, key, value in
             ADDED_TO_CURRENT_LAYOUT + ADDED_AT_THE_OLD_BEHAVIOUR]
    for _, key, section in ADDED_SUBSECTIONS:
        lines.append(f"  {key}:")
        lines += ["    " + line for line in yaml_dump_typed(section()).splitlines()]
    return tuple(lines)


def _without_lines(text: str, lines) -> str:
    for line in lines:
        text = re.sub(f"^{re.escape(line)}\n", "", text, flags=re.MULTILINE)
    return text
ADDED_SECTION_DEFAULTS = (
    "inertia:\n  identify: true\n  prior_weight: 1.0e-12\n  start: 0.2\n"
    "  duration: 10.0\n  change_threshold: 0.05\n",)


@dataclass(eq=False)
class PlanarLayoutV1:
    """A planar scenario's fields, in order, before the robot: and task: sections (frozen).

    Attributes:
        robot: The ground truth (now robot.truth).
        nominal_robot: The controller's model (now robot.nominal).
        q0: The initial joint angles [rad].
        phases: The phases (scenario.Phases).
        lhs: The LHS controller's gains (now task.gains).
        potential: The null-space potential (now robot.potential).
        inertia: The inertial identification (scenario.InertiaIdentification).
        reference: The reference angle (now task.reference).
        rhs: The RHS integrator (scenario.Rhs).
        periods: The periods (scenario.Periods).
        uncertainty: The ground truth's RHS (scenario.Uncertainty).
        disturbance: The disturbance (scenario.Disturbance).
        learner: The learner (scenario.Learner).
        excitation: The excitation (scenario.Excitation).
        stress: The stress (scenario.Stress).
        simulator: Drake's simulator settings.
        seed: The seed."""
    robot: RobotParams = field(default_factory=RobotParams)
    nominal_robot: RobotParams = field(default_factory=RobotParams)
    q0: List[float] = field(default_factory=lambda: [0.3, 1.0])
    phases: Phases = field(default_factory=Phases)
    lhs: LhsGains = field(default_factory=LhsGains)
    potential: Potential = field(default_factory=Potential)
    inertia: InertiaIdentification = field(default_factory=InertiaIdentification)
    reference: Reference = field(default_factory=Reference)
    rhs: Rhs = field(default_factory=Rhs)
    periods: Periods = field(default_factory=Periods)
    uncertainty: Uncertainty = field(default_factory=Uncertainty)
    disturbance: Disturbance = field(default_factory=Disturbance)
    learner: Learner = field(default_factory=Learner)
    excitation: Excitation = field(default_factory=Excitation)
    stress: Stress = field(default_factory=Stress)
    simulator: SimulatorConfig = field(default_factory=FixedStepConfig)
    seed: int = 0

    KEYS = ("nominal_robot", "lhs", "potential", "reference")

    @staticmethod
    def From(scenario: Scenario) -> "PlanarLayoutV1":
        """The same settings in this layout.

        Args:
            scenario: A planar arm's scenario."""
        return PlanarLayoutV1(
            robot=scenario.robot.truth, nominal_robot=scenario.robot.nominal,
            q0=scenario.q0, phases=scenario.phases, lhs=scenario.task.gains,
            potential=scenario.robot.potential, inertia=scenario.inertia,
            reference=scenario.task.reference, **_shared(scenario))

    def ToScenario(self, path: Optional[Union[str, Path]] = None) -> Scenario:
        """The Scenario this file layout describes.

        Args:
            path: The file read (not needed by this layout)."""
        return Scenario(
            robot=PlanarArm(truth=self.robot, nominal=self.nominal_robot,
                            potential=self.potential),
            task=EndEffectorAngle(reference=self.reference, gains=self.lhs),
            q0=self.q0, phases=self.phases, inertia=self.inertia, **_shared(self))

    def SavedForms(self) -> List[str]:
        """Its YAML without later defaults, and the integration_scheme: form if implied."""
        text = _without_lines(yaml_dump_typed(self),
                              ADDED_SETTING_DEFAULTS + _added_lines())
        for section in ADDED_SECTION_DEFAULTS:
            text = re.sub(f"^{re.escape(section)}", "", text, flags=re.MULTILINE)
        config = self.simulator
        if yaml_dump_typed(config) != yaml_dump_typed(FixedStepConfig(
                config.integration_scheme, self.periods.rhs)):
            return [text]
        older = re.sub(r"^simulator:\n(?:  .*\n)*",
                       f"integration_scheme: {config.integration_scheme}\n", text,
                       flags=re.MULTILINE)
        return [text, older]


@dataclass(eq=False)
class SpatialLayoutV1:
    """A described arm's scenario (SpatialScenario) as it stood (a frozen record).

    Attributes:
        robot: The description's name (now robot.description).
        q0: The initial joint angles [rad].
        duration: The run's duration [s] (now the phases' end).
        reference: The reference attitude (now task.reference).
        gains: The attitude controller's gains (now task.gains).
        potential: The clearance potential (now robot.potential).
        nominal_inertia_scale: The controller's model error (robot.nominal_inertia_scale).
        inertia: The inertial identification (scenario.InertiaIdentification).
        phases: The phases (scenario.Phases).
        uncertainty: The ground truth's RHS (scenario.Uncertainty).
        disturbance: The disturbance (scenario.Disturbance).
        rhs: The RHS integrator (scenario.Rhs).
        learner: The learner (scenario.Learner), as it stood then.
        excitation: The excitation (scenario.Excitation).
        stress: The stress (scenario.Stress).
        rhs_period: Now periods.rhs [s].
        lhs_period: Now periods.lhs [s].
        learner_sample_period: Now periods.learner_sample [s].
        learner_period: Now periods.learner [s].
        log_period: Now periods.log [s].
        simulator: Drake's simulator settings.
        seed: The seed."""
    robot: str = "satellite_6dof"
    q0: List[float] = field(default_factory=lambda: [0.3, -0.8, 1.6, 0.2, 0.6, -0.3])
    duration: float = 8.0
    reference: AttitudeReference = field(default_factory=AttitudeReference)
    gains: AttitudeGains = field(default_factory=AttitudeGains)
    potential: ClearancePotential = field(default_factory=ClearancePotential)
    nominal_inertia_scale: List[float] = field(default_factory=list)
    inertia: InertiaIdentification = field(default_factory=InertiaIdentification)
    phases: Phases = field(default_factory=lambda: Phases(
        warmup=2.0, linear=2.0, nonlinear=2.0, disturbance=2.0))
    uncertainty: Uncertainty = field(default_factory=lambda: six_dof_uncertainty(0.0))
    disturbance: Disturbance = field(default_factory=lambda: six_dof_disturbance(0.0))
    rhs: Rhs = field(default_factory=described_arm_rhs)
    learner: Learner = field(default_factory=lambda: replace(     # as it stood then
        described_arm_learner(), prior_fallback=False))
    excitation: Excitation = field(default_factory=Excitation)
    stress: Stress = field(default_factory=Stress)
    rhs_period: float = 5e-4
    lhs_period: float = 1e-3
    learner_sample_period: float = 1e-2
    learner_period: float = 0.1
    log_period: float = 1e-2
    simulator: SimulatorConfig = field(default_factory=FixedStepConfig)
    seed: int = 0

    KEYS = ("duration", "gains", "nominal_inertia_scale", "rhs_period", "lhs_period",
            "learner_sample_period", "learner_period", "log_period")

    def ToScenario(self, path: Union[str, Path]) -> Scenario:
        """The scenario; a duration other than the phases' end resizes phase 3 to end there.

        Args:
            path: The file read, for the message.

        Raises:
            ConfigError: The duration ends before phase 3 starts."""
        phases = self.phases
        if self.duration != phases.end:
            if self.duration < phases.disturbance_start:
                raise ConfigError(
                    f"{path}: duration = {self.duration:g} s ends before phase 3 starts "
                    f"({phases.disturbance_start:g} s); allowed: phases that end at "
                    "the duration (a run lasts as long as its phases)")
            phases.disturbance = self.duration - phases.disturbance_start
        return Scenario(
            robot=DescribedArm(description=self.robot,
                               nominal_inertia_scale=self.nominal_inertia_scale,
                               potential=self.potential),
            task=EndEffectorAttitude(reference=self.reference, gains=self.gains),
            q0=self.q0, phases=phases, inertia=self.inertia,
            periods=Periods(rhs=self.rhs_period, lhs=self.lhs_period,
                            learner=self.learner_period,
                            learner_sample=self.learner_sample_period,
                            log=self.log_period), **_shared(self, periods=False))


# The older file layouts that can express a scenario of each robot section (a saved
# run's fingerprint may come from them); runs of described arms began in the current.
OLDER_LAYOUTS = {PlanarArm: (PlanarLayoutV1,)}


def _shared(settings, periods: bool = True):
    names = ["rhs", "uncertainty", "disturbance", "learner", "excitation", "stress",
             "simulator", "seed"] + (["periods"] if periods else [])
    return {name: getattr(settings, name) for name in names}


def load_older_layout(path: Union[str, Path], saved_run: bool = False
                      ) -> Optional[Scenario]:
    """Reads an older layout's scenario file with a logged note; None: the current layout.

    Args:
        path: The scenario file.
        saved_run: A saved run's: the settings added since as they were.

    Raises:
        ConfigError: The file cannot be read or does not fit its layout."""
    raw = read_yaml(path)
    if not isinstance(raw, dict):
        return None
    robot = raw.get("robot")
    current_robot = isinstance(robot, dict) and (
        getattr(robot, "tag", "") or {"truth", "nominal", "potential"} & set(robot))
    current = sorted(key for key in raw if key not in _field_names(SpatialLayoutV1)
                     and key not in _field_names(PlanarLayoutV1))
    current += ["robot"] if current_robot else []
    if isinstance(robot, str) or any(key in raw for key in SpatialLayoutV1.KEYS):
        layout, note = SpatialLayoutV1, (
            "robot: DESCRIPTION, gains:, reference:, potential:, "
            "nominal_inertia_scale: and the *_period settings are now robot: "
            "!DescribedArm {description, nominal_inertia_scale, potential}, task: "
            "!EndEffectorAttitude {reference, gains} and periods:, and the duration "
            "is the phases' end")
    elif any(key in raw for key in PlanarLayoutV1.KEYS) or (
            isinstance(robot, dict) and not current_robot):
        layout, note = PlanarLayoutV1, (
            "robot:, nominal_robot:, potential:, lhs: and reference: are now robot: "
            "{truth, nominal, potential} and task: {gains, reference}")
    else:
        return None
    older = [key for key in raw if key in layout.KEYS] + (
        ["robot"] if isinstance(robot, str) else [])
    if current:                 # the whole file decides: a mix is neither layout
        raise ConfigError(
            f"{path}: {', '.join(f'{key}:' for key in older)} "
            f"{'is a setting' if len(older) == 1 else 'are settings'} of the layout "
            "before the robot: and task: sections, "
            f"{', '.join(f'{key}:' for key in current)} of the current one; allowed: "
            f"one layout ({note})")
    logging.getLogger(__name__).warning(
        "%s: read in the layout before the robot: and task: sections (%s); save it "
        "again to update the file", path, note)
    if saved_run:
        return load_yaml_dataclass(path, layout,
                                   migrate=_migrate_older_saved_file).ToScenario(path)
    scenario = load_yaml_dataclass(path, layout, migrate=_migrate_file).ToScenario(path)
    note_changed_defaults(raw, scenario, path)
    return scenario


def _field_names(layout) -> Tuple[str, ...]:
    return tuple(f.name for f in dataclasses.fields(layout))


def load_scenario(path: Union[str, Path]) -> Scenario:
    """Loads and validates a scenario, settings the file leaves out at their defaults (no
    robot: the paper's arm, with a warning); older layouts load with a logged note.

    Args:
        path: A YAML file, or a built-in name (BUILT_IN_SCENARIOS) if no file has that name.

    Raises:
        ConfigError: No such file or name, bad YAML, or a bad key, type or value (named)."""
    return _load(path, saved_run=False)


def load_saved_scenario(path: Union[str, Path]) -> Scenario:
    """Loads a saved run's scenario.yaml as it ran: later settings it lacks at old values.

    Args:
        path: The run directory's scenario.yaml.

    Raises:
        ConfigError: As load_scenario."""
    return _load(path, saved_run=True)


def _load(path: Union[str, Path], saved_run: bool) -> Scenario:
    """load_scenario's body; ``saved_run`` reads the settings added since as they were."""
    if str(path) in BUILT_IN_SCENARIOS and not Path(path).is_file():
        return BUILT_IN_SCENARIOS[str(path)]()
    if not Path(path).is_file():
        close = difflib.get_close_matches(str(path), list(BUILT_IN_SCENARIOS), n=1)
        raise ConfigError(f"scenario {str(path)!r}: no such file; allowed: a scenario "
                          f"YAML file or a built-in name ({', '.join(BUILT_IN_SCENARIOS)})"
                          + (f"; did you mean {close[0]!r}?" if close else ""))
    scenario = load_older_layout(path, saved_run) or _load_current_layout(path,
                                                                          saved_run)
    robot_kind(scenario.robot).ResolvePaths(scenario.robot,
                                            Path(path).resolve().parent)  # paths in the file
    validate_scenario(scenario)
    return scenario


def _load_current_layout(path, saved_run: bool) -> Scenario:
    """A current-layout file over its robot's defaults (sized_defaults)."""
    migrate = _migrate_saved_file if saved_run else _migrate_file
    scenario = load_yaml_dataclass(path, Scenario, noted_defaults=("robot",),
                                   migrate=migrate)
    robot_kind(scenario.robot).ResolvePaths(scenario.robot,
                                            Path(path).resolve().parent)  # before it is parsed
    raw = read_yaml(path)
    given = raw if isinstance(raw, dict) else {}
    defaults = sized_defaults(scenario.robot,
        scenario.q0 if "q0" in given else None,
        scenario.task if "task" in given else None)
    if defaults is None:
        return scenario
    return load_yaml_dataclass(path, Scenario, migrate=migrate, defaults=defaults)


def _migrate_older_saved_file(raw, path):
    """_migrate_saved_file, the added sections an older layout's file lacks added too."""
    if isinstance(raw, dict):
        raw = {**raw, **{section: {} for section, _, _ in ADDED_TO_CURRENT_LAYOUT
                         if section not in raw}}
    migrated = _migrate_saved_file(raw, path)
    return raw if migrated is None else migrated


def _migrate_saved_file(raw, path):
    """_migrate_file, then each added setting a section lacks at its value before it."""
    migrated = _migrate_file(raw, path)
    source = migrated if migrated is not None else raw
    if not isinstance(source, dict):
        return migrated
    for section, key, before in ADDED_TO_CURRENT_LAYOUT:
        if isinstance(source.get(section), dict) and key not in source[section]:
            source = dict(source)
            source[section] = {**source[section], key: before}
    for section, key, introduced in ADDED_SUBSECTIONS:
        if isinstance(source.get(section), dict) and key not in source[section]:
            source = dict(source)
            source[section] = {**source[section],
                               key: dataclasses.asdict(introduced())}
    return source if source is not raw else None


def _migrate_file(raw, path):
    """move_integration_scheme, and a q0 by joint name as a list (None: no change)."""
    migrated = move_integration_scheme(raw, path)
    source = migrated if migrated is not None else raw
    if isinstance(source, dict) and isinstance(source.get("q0"), dict):
        return {**source, "q0": q0_by_joint_name(source, path)}
    return migrated


def note_changed_defaults(raw: Dict, scenario: Scenario, path: Union[str, Path]) -> None:
    """Logs each added setting an older file leaves out whose default has changed since.

    Args:
        raw: The parsed file.
        scenario: The scenario it loaded into.
        path: The file, for the note."""
    changed = []
    for section, key, before in ADDED_TO_CURRENT_LAYOUT:
        named = isinstance(raw.get(section), dict) and key in raw[section]
        now = getattr(getattr(scenario, section), key)
        if not named and now != before:
            changed.append(f"{section}.{key} = {now!r} (before it existed: {before!r})")
    if changed:
        logging.getLogger(__name__).warning(
            "%s: settings whose default changed since this file's layout now run at "
            "today's: %s; name them in the file to run them otherwise", path,
            "; ".join(changed))


def q0_by_joint_name(raw: Dict, path: Union[str, Path]) -> List[float]:
    """A q0 given as joint name -> angle, as the list [rad] in q's order (described arms).

    Args:
        raw: The parsed scenario file (its q0 a mapping).
        path: The file (relative description paths are relative to its folder).

    Raises:
        ConfigError: An unknown joint (and the closest), joints left out, no description."""
    import json

    from pydrake.common.yaml import yaml_dump, yaml_load_typed

    mapping, robot = raw["q0"], raw.get("robot")
    if not (isinstance(robot, dict) and "description" in robot):
        raise ConfigError(f"{path}: q0 is given by joint name; allowed: by name only "
                          "for an arm from its description (robot: !DescribedArm), "
                          "else a list with one angle per joint")
    arm = yaml_load_typed(schema=DescribedArm, data=yaml_dump(json.loads(json.dumps(
        robot))))                       # the loader's tagged mapping, as plain data
    robot_kind(arm).ResolvePaths(arm, Path(path).resolve().parent)
    names = robot_kind(arm).JointNames(arm)
    for name in mapping:
        if name not in names:
            close = difflib.get_close_matches(str(name), names, n=1)
            raise ConfigError(
                f"q0.{name} is not a joint of the arm"
                + (f" (did you mean {close[0]!r}?)" if close else "")
                + f"; allowed: {', '.join(names)}")
    missing = [name for name in names if name not in mapping]
    if missing:
        raise ConfigError(f"q0 leaves out the joints {', '.join(missing)}; allowed: "
                          f"every joint of the arm by name ({', '.join(names)}), or "
                          "no q0 (a start is chosen)")
    return [float(mapping[name]) for name in names]


def move_integration_scheme(raw: object, path: Union[str, Path]) -> Optional[Dict]:
    """The parsed file with a top-level ``integration_scheme: X`` read as ``simulator:
    {integration_scheme: X, max_step_size: periods.rhs}``, noted; None without that key.

    Args:
        raw: The parsed scenario file.
        path: The file, for the messages.

    Raises:
        ConfigError: The file sets both integration_scheme: and simulator:."""
    if not (isinstance(raw, dict) and "integration_scheme" in raw):
        return None
    if "simulator" in raw:
        raise ConfigError(f"{path}: both integration_scheme: and simulator: are set; "
                          "allowed: simulator: {integration_scheme: ...} only")
    migrated = dict(raw)
    migrated["simulator"] = {"integration_scheme": migrated.pop("integration_scheme")}
    periods = raw.get("periods")
    if isinstance(periods, dict) and "rhs" in periods:     # the step it implied
        migrated["simulator"]["max_step_size"] = periods["rhs"]
    logging.getLogger(__name__).warning(
        "%s: integration_scheme: is read as simulator: {integration_scheme: %s} (the "
        "scenario now embeds Drake's SimulatorConfig; save it again to update the file)", path,
        migrated["simulator"]["integration_scheme"])
    return migrated


def saved_forms(scenario: Scenario) -> List[str]:
    """The YAML texts a saved run may have been fingerprinted from: its form without later
    settings at their defaults, then its older layouts' (OLDER_LAYOUTS).

    Args:
        scenario: The scenario."""
    return [_without_lines(_without_default_sections(yaml_dump_typed(scenario)),
                           _added_lines())] + [
        form for layout in OLDER_LAYOUTS.get(type(scenario.robot), ())
        for form in layout.From(scenario).SavedForms()]


def save_scenario(scenario: Scenario, path: Union[str, Path]) -> None:
    """Writes a scenario as YAML (load_scenario reads it back).

    Args:
        scenario: The scenario.
        path: The file to write."""
    with open(path, "w") as f:
        f.write(yaml_dump_typed(scenario))

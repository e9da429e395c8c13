"""A scenario: every setting of a closed-loop run, in one room.

- schema: the sections as typed data (Scenario and its sections; the names below);
- planar_arm: the planar arm's description (RobotParams), a section of the schema;
- simulator: the ``simulator:`` section (Drake's SimulatorConfig) and its check;
- yaml_files: YAML read with every key and kind checked against the schema;
- checks: every setting's allowed range, one line naming it;
- built_in: the named scenarios shipped in code;
- errors: ConfigError and the checks that raise it, one line naming the setting.

Scenario files (reading one sized to its robot, saving, the layouts of earlier
releases) are assembly.scenario_files'; sizing is each robot kind's (robots.sizing).

``from dacph_drake.scenario import Scenario, Phases, ...`` reads the schema."""
from dacph_drake.scenario.schema import (  # noqa: F401
    ADOPTIONS, EFFORT_LIMITS, GAIN_RULES, INERTIA_ANCHORS, JOINT_DAMPING, JOINT_FRICTION,
    JOINT_LIMITS, LEARNER_COUPLINGS, LEARNER_MODES, LEARNER_PRIOR_SCALES,
    ON_MISMATCH, TRUST_ANCHORS, ActuatorFault, ArmBase, AttitudeGains, AttitudeReference,
    ClearancePotential, DescribedArm, Disturbance, EndEffectorAngle, EndEffectorAttitude,
    EndEffectorFrame, EndEffectorPose, EndEffectorPosition, Excitation,
    InertiaIdentification, Learner, LhsGains, LocalBayes, Periods, Phases, PlanarArm,
    PositionReference, Potential, Reference, Rhs, Scenario, Stress, Uncertainty,
    add_section_type)

"""A scenario, every setting of a closed-loop run: schema (Scenario and its sections),
planar_arm (RobotParams), simulator (Drake's SimulatorConfig), yaml_files (YAML checked
against the schema), checks (allowed ranges), built_in (named scenarios), errors
(ConfigError). Files: assembly.scenario_files; sizing: robots.sizing."""
from dacph_drake.scenario.schema import (  # noqa: F401
    ADOPTIONS, EFFORT_LIMITS, GAIN_RULES, INERTIA_ANCHORS, JOINT_DAMPING, JOINT_FRICTION,
    JOINT_LIMITS, RATE_SOURCES, LEARNER_COUPLINGS, LEARNER_MODES, LEARNER_PRIOR_SCALES,
    ON_MISMATCH, TRUST_ANCHORS, ActuatorFault, ArmBase, AttitudeGains, AttitudeReference,
    ClearancePotential, DescribedArm, Disturbance, EndEffectorAngle, EndEffectorAttitude,
    EndEffectorFrame, EndEffectorPose, EndEffectorPosition, Excitation,
    InertiaIdentification, Learner, LhsGains, LocalBayes, Periods, Phases, PlanarArm,
    PositionReference, Potential, Reference, Rhs, Scenario, Sensing, Stress, Uncertainty,
    add_section_type)

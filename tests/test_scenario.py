"""Scenario files: the shipped ones load, and bad input gets a clear error."""
from pathlib import Path

import pytest

from dacph_drake.controllers.dac import build_dac_diagram
from dacph_drake.scenario.errors import ConfigError
from pydrake.common.yaml import yaml_dump_typed

from dacph_drake.scenario import Scenario
from dacph_drake.scenario.built_in import BUILT_IN_SCENARIOS
from dacph_drake.assembly.scenario_files import load_scenario, save_scenario, saved_forms
from dacph_drake.assembly.registry import validate_scenario

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


@pytest.mark.parametrize("name", ["paper", "short"])
def test_shipped_scenarios_load(name):
    scenario = load_scenario(SCENARIOS / f"{name}.yaml")
    assert scenario.duration == (1500.0 if name == "paper" else 26.0)
    assert scenario == BUILT_IN_SCENARIOS[name]()       # the files match the built-ins


def test_yaml_round_trip(tmp_path):
    save_scenario(Scenario(seed=7), tmp_path / "s.yaml")
    assert load_scenario(tmp_path / "s.yaml") == Scenario(seed=7)


# Scenario files that must be refused, and a pattern the one-line message must
# match (it names the setting); the CLI's table in test_reliability runs them too.
BAD_SCENARIO_FILES = [
    ("task: {gains: {Kd: 0.5, gain: 1}}\n", r"s.yaml.*gain"),
    ("task: {gains: {Kd: fast}}\n", r"s.yaml.*fast"),
    ("task: {gains: {Kd: -0.5}}\n", r"task.gains.Kd = -0.5 .*> 0"),
    ("periods: {rhs: 0.0}\n", r"periods.rhs = 0.0 .*> 0 s"),
    ("periods: {lhs: 0.5}\n", r"periods.lhs = 0.5 s must not exceed periods.learner_sample"),
    ("robot: {nominal: {base: {mass: -2.0}}}\n", r"robot.nominal.base.mass = -2.0"),
    ("q0: [0.1]\n", r"q0 has 1 entries; allowed: 2"),
    ("integration_scheme: euler\n", r"integration_scheme = 'euler'; allowed"),
    ("uncertainty: {B_linear: [[1.0]]}\n", r"uncertainty.B_linear must be a 2 x 2"),
    ("rhs: {trust_ratio: 0.5}\n", r"rhs.trust_ratio = 0.5 .*in \[1, 10\]"),
    ("stress: {B_hat_scale: 0.0}\n", r"stress.B_hat_scale = 0.0 .*> 0"),
    ("stress: {start: -1.0}\n", r"stress.start = -1.0 .*>= 0 s"),
    ("learner: {mode: adaptive}\n", r"learner.mode = 'adaptive'; allowed: regularized, "
                                    r"plain"),
    ("learner: {prior_scale: per_output}\n", r"learner.prior_scale = 'per_output'; "
                                            r"allowed: pooled, per_input"),
    ("learner: {coupling: full}\n", r"learner.coupling = 'full'; allowed: uniform, "
                                     r"inertia"),
    ("learner: {band: [1.0]}\n", r"learner.band has 1 entries; allowed: 2 \(\[low, "
                                 r"high\] in Hz\)"),
    ("learner: {band: [2.0, 60.0]}\n", r"learner.band\[1\] = 60.0 .*in \[2, 50\] Hz"),
    ("learner: {band_sections: [4, 40]}\n", r"learner.band_sections\[1\] = 40 .*\[0, 16\]"),
    ("learner: {forgetting: 0.0}\n", r"learner.forgetting = 0.0 .*> 0 s"),
    ("learner: {prior_weight: -1.0}\n", r"learner.prior_weight = -1.0 .*>= 0"),
    ("learner: {change_ratio: 0.5}\n", r"learner.change_ratio = 0.5 .*\[1, 1e\+06\]"),
    ("excitation: {amplitude: .nan}\n", r"excitation.amplitude = nan .*>= 0 N m"),
    ("excitation: {frequencies: [5.0, 4.0]}\n",
     r"excitation.frequencies\[1\] = 4.0 .*in \[5, 500\] Hz"),
    ("excitation: {frequencies: [0.5, 4.0]}\n",
     r"excitation.frequencies = \[0.5, 4.0\] Hz lie outside learner.band"),
    ("excitation: {joint_scale: [0.5]}\n",
     r"excitation.joint_scale has 1 entries; allowed: 2 \(one per joint, or none\)"),
    ("excitation: {joint_scale: [0.5, 1.5]}\n",
     r"excitation.joint_scale\[1\] = 1.5 .*\[0, 1\]"),
    # Non-finite numbers anywhere, and settings that cannot run together.
    ("q0: [.nan, 1.0]\n", r"q0\[0\] = nan is not finite; allowed: a finite number"),
    ("q0: [0.3, .inf]\n", r"q0\[1\] = inf is not finite"),
    ("task: {reference: {amplitudes: [.nan, 0.1]}}\n",
     r"task.reference.amplitudes\[0\] = nan"),
    ("uncertainty: {B_linear: [[.nan, 0.0], [0.05, 0.15]]}\n",
     r"uncertainty.B_linear\[0\]\[0\] = nan is not finite"),
    ("disturbance: {hf_amplitude: .nan}\n", r"disturbance.hf_amplitude = nan"),
    ("disturbance: {start: .nan}\n", r"disturbance.start = nan is not finite"),
    ("disturbance: {lf_offset: [.inf, 0.0]}\n", r"disturbance.lf_offset\[0\] = inf"),
    ("robot: {truth: {links: [{mass: 1.0, length: .nan}, {mass: 1.0}]}}\n",
     r"robot.truth.links\[0\]"),
    ("seed: -1\n", r"seed = -1 is out of range; allowed: in \[0, 4\.29497e\+09\]"),
    ("periods: {log: 100.0}\nphases: {warmup: 1.0, linear: 1.0, nonlinear: 1.0, "
     "disturbance: 1.0}\n", r"periods.log = 100 s is longer than the run \(4 s"),
    ("rhs: {beta_max: 0.5}\n", r"rhs.beta_max = 0.5 is out of range; allowed: in \[1, "),
    ("task: {gains: {min_task_singular_value: -0.1}}\n",
     r"task.gains.min_task_singular_value = -0.1 is out of range; allowed: in \[0, 10\]"),
    # Drake's SimulatorConfig, embedded as simulator:.
    ("simulator: {integration_scheme: radau3}\n",
     r"simulator.integration_scheme = 'radau3'; allowed: runge_kutta2, runge_kutta3"),
    ("simulator: {max_step_size: 0.0}\n",
     r"simulator.max_step_size = 0.0 is out of range; allowed: in \[1e-07, 1\] s"),
    ("simulator: {use_error_control: true}\n",
     r"simulator.use_error_control = true with simulator.integration_scheme = "
     r"'runge_kutta2', which has no error estimate"),
    ("simulator: {integration_scheme: runge_kutta3, use_error_control: true, "
     "accuracy: .nan}\n", r"simulator.accuracy = nan is out of range"),
    ("simulator: {start_time: 1.0}\n", r"simulator.start_time = 1 s; allowed: 0"),
    ("simulator: {target_realtime_rate: -1.0}\n",
     r"simulator.target_realtime_rate = -1.0 is out of range; allowed: >= 0"),
    ("simulator: {publish_every_time_step: true}\n",
     r"simulator.publish_every_time_step = true; allowed: false"),
    ("simulator: {step: 0.001}\n", r"s.yaml.*step"),
    ("integration_scheme: runge_kutta3\nsimulator: {max_step_size: 0.001}\n",
     r"s.yaml: both integration_scheme: and simulator: are set"),
    # model error (docs/results/model-error.md)
    ("uncertainty: {B_scale: [1.0]}\n", r"uncertainty.B_scale has 1 entries"),
    ("uncertainty: {B_scale: [1.0, 0.0]}\n", r"uncertainty.B_scale\[1\] = 0.0 .*in \[0.01"),
    ("uncertainty: {faults: [{time: -1.0, joint: 1, gain: 0.5}]}\n",
     r"uncertainty.faults\[0\].time = -1.0 .*>= 0"),
    ("uncertainty: {faults: [{time: 1.0, joint: 3, gain: 0.5}]}\n",
     r"uncertainty.faults\[0\].joint = 3 .*in \[1, 2\]"),
    ("uncertainty: {faults: [{time: 1.0, joint: 1, gain: 0.0}]}\n",
     r"uncertainty.faults\[0\].gain = 0.0 .*in \[0.01"),
    ("uncertainty: {faults: [{time: 1.0, joint: 1.5, gain: 0.5}]}\n",
     r"int.* value for 'joint'"),
    ("rhs: {trust_anchor: B0}\n", r"rhs.trust_anchor = 'B0'; allowed: in_use, prior"),
    ("rhs: {evidence_ratio: 2.0}\n", r"rhs.evidence_ratio = 2.0 .*in \[0, 1\]"),
    ("rhs: {evidence_window: 0.0}\n", r"rhs.evidence_window = 0.0 .*> 0"),
    ("rhs: {gain_rule: fast}\n", r"rhs.gain_rule = 'fast'; allowed: paper, well_damped"),
    ("task: {gains: {boundary_rate: -1.0}}\n", r"task.gains.boundary_rate = -1.0 .*>= 0"),
    ("learner: {start_hold: -1.0}\n", r"learner.start_hold = -1.0 .*>= 0"),
    ("learner: {min_window: 10.0}\n", r"learner.min_window = 10.0 .*in \[0, 4\]"),
    ("learner: {step_guard: 0.5}\n", r"learner.step_guard = 0.5 .*in \[1, 1e\+12\]"),
    ("learner: {prior_fallback: sometimes}\n", r"s.yaml.*bool.*prior_fallback.*sometimes"),
    ("inertia: {prior_weight: 0.0}\n", r"inertia.prior_weight = 0.0 .*in \[1e-14, 1\]"),
    ("inertia: {start: -0.1}\n", r"inertia.start = -0.1 .*>= 0"),
    ("inertia: {change_threshold: 2.0}\n", r"inertia.change_threshold = 2.0 .*in \[0, 1\]"),
    ("inertia: {duration: 0.0}\n", r"inertia.duration = 0.0 .*> 0"),
    # trustworthy learning (docs/results/learning.md)
    ("learner: {model: gp}\n", r"learner.model = 'gp'; allowed: local_bayes, network"),
    ("rhs: {adoption: always}\n",
     r"rhs.adoption = 'always'; allowed: certified_set, trust_band"),
    ("inertia: {anchor: payload}\n",
     r"inertia.anchor = 'payload'; allowed: total_mass, base_mass, model"),
    ("inertia: {anchor_mass: -1.0}\n", r"inertia.anchor_mass = -1.0 .*>= 0 kg"),
    ("inertia: {anchor_error: 0.9}\n", r"inertia.anchor_error = 0.9 .*in \[-0.5, 0.5\]"),
    ("inertia: {nominal_tolerance: 1.0}\n",
     r"inertia.nominal_tolerance = 1.0 .*in \[0, 0.999\]"),
    ("inertia: {anchor_tolerance: -0.1}\n",
     r"inertia.anchor_tolerance = -0.1 .*in \[0, 0.5\]"),
    ("inertia: {kinematic_tolerance: 0.8}\n",
     r"inertia.kinematic_tolerance = 0.8 .*in \[0, 0.5\]"),
    ("inertia: {error_draws: 1}\n", r"inertia.error_draws = 1 .*in \[2, 256\]"),
    ("inertia: {error_draws: 2.5}\n", r"error_draws.*whole number"),
    ("inertia: {fit_tolerance: -1.0e-5}\n", r"inertia.fit_tolerance = -1e-05 .*>= 0"),
    ("inertia: {on_mismatch: ignore}\n",
     r"inertia.on_mismatch = 'ignore'; allowed: identified, nominal"),
    ("learner: {bayes: {gain_range: [0.5]}}\n",
     r"learner.bayes.gain_range has 1 entries; allowed: 2"),
    ("learner: {bayes: {gain_range: [1.5, 2.0]}}\n",
     r"learner.bayes.gain_range\[0\] = 1.5 .*in \[0.001, 1\]"),
    ("learner: {bayes: {gain_range: [0.5, 200.0]}}\n",
     r"learner.bayes.gain_range\[1\] = 200.0 .*in \[1, 100\]"),
    ("learner: {bayes: {coupling: 2.0}}\n", r"learner.bayes.coupling = 2.0 .*in \[0, 1\]"),
    ("learner: {bayes: {damping_range: [-0.1, 2.0]}}\n",
     r"learner.bayes.damping_range\[0\] = -0.1 .*in \[0, 1\]"),
    ("learner: {bayes: {drift: 0.0}}\n", r"learner.bayes.drift = 0.0 .*> 0 1/s"),
    ("learner: {bayes: {momentum_slope: -1.0}}\n",
     r"learner.bayes.momentum_slope = -1.0 .*> 0"),
    ("learner: {bayes: {curvature: -0.01}}\n", r"learner.bayes.curvature = -0.01 .*>= 0"),
    ("learner: {bayes: {floor: -1.0}}\n", r"learner.bayes.floor = -1.0 .*>= 0"),
    ("learner: {bayes: {forgetting: 0.0}}\n", r"learner.bayes.forgetting = 0.0 .*> 0 s"),
    ("learner: {bayes: {min_window: 100.0}}\n",
     r"learner.bayes.min_window = 100.0 .*at most learner.window"),
    ("learner: {bayes: {min_dof: 0.5}}\n", r"learner.bayes.min_dof = 0.5 .*in \[1, "),
    ("learner: {bayes: {credible_level: 1.0}}\n",
     r"learner.bayes.credible_level = 1.0 .*in \[0.01, 0.999\]"),
    ("learner: {bayes: {certificate_level: 0.5}}\n",
     r"learner.bayes.certificate_level = 0.5 .*at least learner.bayes.credible_level"),
    ("learner: {bayes: {margin: -1.0}}\n", r"learner.bayes.margin = -1.0 .*>= 0"),
    ("learner: {bayes: {change_floor: -0.1}}\n", r"learner.bayes.change_floor = -0.1 .*>= 0"),
    ("learner: {bayes: {inconsistency: 0.001}}\n",
     r"learner.bayes.inconsistency = 0.001; allowed: a number above "
     r"learner.bayes.change_floor"),
    ("learner: {bayes: {model_error: 1.0}}\n",
     r"learner.bayes.model_error = 1.0 .*in \[0, 0.999\]"),
    ("learner: {bayes: {prior: wide}}\n", r"s.yaml.*\['prior'\] were unknown"),
    # A mistyped key names its section and the closest setting.
    ("learner: {bayes: {credible_levl: 0.9}}\n",
     r"learner.bayes: the fields \['credible_levl'\] were unknown \(did you mean "
     r"'credible_level'\?\); allowed: "),
    ("sed: 3\n", r"top level: the fields \['sed'\] were unknown \(did you mean 'seed'\?\)"),
    ("robot: !DescribedArm\n  description: satellite_3dof\n  base: {mas: 3.0}\n",
     r"robot.base: the fields \['mas'\] were unknown \(did you mean 'mass'\?\); "
     r"allowed: mass, size, mount"),
    # Whole numbers, keys given once.
    ("uncertainty: {faults: [{time: 1.0, joint: 1.5, gain: 0.5}]}\n",
     r"uncertainty.faults\[0\].joint = 1.5 is not a whole number"),
    ("learner: {hidden: [16.5, 8]}\n", r"learner.hidden\[0\] = 16.5 is not a whole number"),
    ("q0: [0.3, 1.0]\nseed: 2\nq0: [0.2, 1.0]\n",
     r"q0 is given twice \(lines 1 and 3\); allowed: each setting once"),
    # Events after the run's end never take effect.
    ("uncertainty: {faults: [{time: 1500.0, joint: 2, gain: 0.5}]}\n",
     r"uncertainty.faults\[0\].time = 1500 s is at or after the run's end \(1500 s"),
    ("disturbance: {start: 1600.0}\n",
     r"disturbance.start = 1600 s is at or after the run's end \(1500 s"),
    ("stress: {B_hat_scale: 2.0, start: 2000.0}\n",
     r"stress.start = 2000 s is at or after the run's end"),
    # A reference the sized defaults cannot size by.
    ("robot: !DescribedArm\n  description: satellite_3dof\ntask: !EndEffectorAttitude\n"
     "  reference: {period: 0.0}\n", r"task.reference.period = 0.0 is out of range; "
                                     r"allowed: > 0 s"),
    ("robot: {truth: {links: [{mass: 1.0, length: 0.5, com: 0.25, inertia: 0.02}, "
     "{mass: 1.0, length: 0.5, com: 0.25, inertia: 0.02}, {mass: 1.0, length: 0.5, "
     "com: 0.25, inertia: 0.02}]}}\ntask: {reference: {periods: [0.0, 11.0]}}\n",
     r"task.reference.periods\[0\] = 0.0 is out of range; allowed: > 0 s"),
    # One stray key of the older layout in a current file: the whole file decides.
    ("robot: !DescribedArm\n  description: satellite_3dof\nduration: 5.0\n",
     r"duration: is a setting of the layout before the robot: and task: sections, "
     r"robot: of the current one; allowed: one layout"),
    ("task: {gains: {Kd: 0.5}}\nlhs: {Kd: 0.5}\n",
     r"lhs: is a setting of the layout before .* task: of the current one"),
]


def test_files_of_the_older_layout_load(tmp_path, caplog):
    """A top-level integration_scheme: (before the scenario embedded Drake's
    SimulatorConfig) is read as simulator: {integration_scheme, max_step_size:
    periods.rhs}, with a note; saved runs of it still belong to the scenario."""
    from dacph_drake.loop.run_store import scenario_fingerprints
    from dacph_drake.scenario.simulator import FixedStepConfig
    path = tmp_path / "s.yaml"
    path.write_text("integration_scheme: runge_kutta3\nperiods: {rhs: 1.25e-4}\n")
    scenario = load_scenario(path)
    assert "integration_scheme: is read as simulator:" in caplog.text
    assert yaml_dump_typed(scenario.simulator) == yaml_dump_typed(
        FixedStepConfig("runge_kutta3", 1.25e-4))
    # This layout's, the one before the robot: and task: sections, and that one's
    # with the old key.
    current, before_sections, legacy = scenario_fingerprints(scenario)
    assert current != legacy
    # The older layout's text is the dump of the same settings with the old key.
    assert "integration_scheme: runge_kutta3\n" in saved_forms(scenario)[2]
    assert "simulator:" not in saved_forms(scenario)[2]
    save_scenario(scenario, path)
    assert load_scenario(path) == scenario
    scenario.simulator.max_step_size = 1e-4     # not what the old key implied
    assert len(scenario_fingerprints(scenario)) == 2


def test_files_written_before_a_setting_was_added_keep_their_meaning(tmp_path):
    """A spatial scenario file as the release before learner.prior_fallback wrote
    it (the shipped satellite_3dof without that line), saved with a run, is read with
    the fallback off, as it ran (load_saved_scenario), not with the sized default's
    on, and its fingerprinted text is the file as written
    (assembly.scenario_files.ADDED_TO_CURRENT_LAYOUT); the shipped file itself keeps it on. As
    an input file, the same text runs the setting at its current default."""
    from dacph_drake.assembly.scenario_files import load_saved_scenario
    shipped = (SCENARIOS / "satellite_3dof.yaml").read_text()
    assert "  prior_fallback: true\n" in shipped
    # The release before wrote neither that line nor excitation.joint_scale's.
    before = shipped.replace("  prior_fallback: true\n", "").replace(
        "  joint_scale: []\n", "")
    path = tmp_path / "before.yaml"
    path.write_text(before)
    assert load_scenario(path).learner.prior_fallback
    scenario = load_saved_scenario(path)
    assert not scenario.learner.prior_fallback
    assert saved_forms(scenario)[0] == before
    assert load_scenario(SCENARIOS / "satellite_3dof.yaml").learner.prior_fallback


def test_files_of_the_layout_before_robot_and_task_sections_load(tmp_path, caplog):
    """A planar file with top-level robot:, nominal_robot:, lhs:, potential:,
    reference: and a spatial file with robot: DESCRIPTION, gains:, flat periods and
    a duration load with a note, into the same settings (those of the release that
    wrote them: the settings added since at their values before, as_before_added);
    a paper run saved in the older layout (results/paper as committed before the
    learning settings, kept in tests/data) keeps its fingerprint, so report() still
    reads it."""
    import json
    from dacph_drake.app.reproduce import check_runs_belong_together
    from dacph_drake.assembly.scenario_files import (PlanarLayoutV1, as_before_added,
                                            load_saved_scenario)
    results = Path(__file__).resolve().parent / "data" / "paper_run_before_sections"
    with caplog.at_level("WARNING"):
        scenario = load_saved_scenario(results / "scenario.yaml")
    assert "read in the layout before the robot: and task: sections" in caplog.text
    assert scenario == as_before_added(BUILT_IN_SCENARIOS["paper"]())
    runs = {c: json.loads((results / f"run_{c}.json").read_text())
            for c in ("dac", "dac-nominal", "model-based")}
    check_runs_belong_together(results, scenario, runs)
    assert runs["dac"]["scenario_fingerprint"] in [
        f[:16] for f in (__import__("hashlib").sha256(t.encode()).hexdigest()
                         for t in saved_forms(scenario))]
    path = tmp_path / "old.yaml"
    path.write_text(yaml_dump_typed(PlanarLayoutV1.From(BUILT_IN_SCENARIOS["short"]())))
    assert load_scenario(path) == BUILT_IN_SCENARIOS["short"]()
    path.write_text("robot: satellite_3dof\nq0: [0.3, -0.8, 1.6]\nduration: 14.0\n"
                    "phases: {warmup: 2.0, linear: 4.0, nonlinear: 4.0, disturbance: 3.0}\n"
                    "gains: {Lambda: 3.0}\nrhs_period: 2.5e-4\n"
                    "uncertainty: {B0: [1.0, 1.0, 1.0], D0: [0.2, 0.2, 0.01], "
                    "D_offset: [0.04, 0.05, 0.002], D_linear: [0.15, 0.05, 0.1], "
                    "D_quadratic: [0.1, -0.01, 1.0], B_linear: [[-0.1, 0.0, 0.0], "
                    "[0.05, 0.15, 0.0], [0.0, 0.0, 0.1]], B_quadratic: [0.5, 0.02, 5.0], "
                    "B_q1_squared: [[0.0, -0.1, 0.0], [0.4, 0.0, 0.0], [0.0, 0.0, 0.0]]}\n"
                    "disturbance: {lf_offset: [0.03, -0.02, 0.002], lf_amplitude: [0.02, "
                    "0.02, 0.002], lf_frequency: [0.05, 0.07, 0.09], hf_direction: [1.0, "
                    "-1.0, 0.1]}\n")
    old = load_scenario(path)
    assert old.robot.description == "satellite_3dof" and old.task.gains.Lambda == 3.0
    assert old.periods.rhs == 2.5e-4 and old.duration == 14.0     # the last phase: 4 s
    assert old.phases.disturbance == 4.0


def test_the_simulator_settings_reach_drake():
    """loop.CreateSimulator() applies scenario.simulator: scheme, step, real-time
    rate."""
    from pydrake.systems.analysis import RungeKutta3Integrator
    from dacph_drake.controllers.model_based import build_model_based_diagram
    scenario = BUILT_IN_SCENARIOS["short"]()
    scenario.simulator.integration_scheme = "runge_kutta3"
    scenario.simulator.max_step_size = 1e-4
    scenario.simulator.target_realtime_rate = 3.0
    simulator = build_model_based_diagram(scenario).CreateSimulator()
    assert isinstance(simulator.get_integrator(), RungeKutta3Integrator)
    assert simulator.get_integrator().get_maximum_step_size() == 1e-4
    assert simulator.get_target_realtime_rate() == 3.0


@pytest.mark.parametrize("text, message", BAD_SCENARIO_FILES)
def test_bad_input_is_named(tmp_path, text, message):
    path = tmp_path / "s.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_scenario(path)


def test_rhs_period_too_long_for_the_gain_rule():
    scenario = Scenario()
    scenario.periods.rhs = 5e-4
    with pytest.raises(ConfigError, match=r"periods.rhs = 0.0005 s cannot realize the RHS "
                                          r"decay rate c = 8\d\d.\d 1/s .* <= 1 / \(4 c\)"):
        build_dac_diagram(scenario)


def test_plain_learner_needs_no_band():
    """The paper's plain learner ignores the band, so an excitation outside it is
    allowed (and useless to it)."""
    scenario = Scenario()
    scenario.learner.mode = "plain"
    scenario.excitation.frequencies = [0.5, 0.7]
    validate_scenario(scenario)


def test_a_string_set_from_python_names_the_field():
    scenario = Scenario()
    scenario.q0 = [0.3, "1.0"]
    with pytest.raises(ConfigError, match=r"q0\[1\] = '1.0' is not a number"):
        validate_scenario(scenario)
    scenario = Scenario()
    scenario.seed = 1.5
    with pytest.raises(ConfigError, match=r"seed = 1.5 is not an integer"):
        validate_scenario(scenario)


def test_built_in_names_load_and_unknown_ones_are_named(tmp_path):
    assert load_scenario("short") == BUILT_IN_SCENARIOS["short"]()
    assert load_scenario("paper") == BUILT_IN_SCENARIOS["paper"]()
    with pytest.raises(ConfigError, match=r"scenario 'shrot': no such file; allowed: a "
                                          r"scenario YAML file or a built-in name "
                                          r"\(paper, short, satellite_6dof, satellite_3dof\)"):
        load_scenario("shrot")
    with pytest.raises(ConfigError, match=r"no such file"):
        load_scenario(tmp_path)                            # a directory


@pytest.mark.parametrize("duration", [-1.0, 0.0, float("nan"), float("inf")])
def test_simulate_refuses_a_bad_duration_before_building(duration):
    from dacph_drake.loop.simulate import simulate
    with pytest.raises(ConfigError, match=r"duration = .* allowed: > 0 s"):
        simulate(BUILT_IN_SCENARIOS["short"](), "dac", duration=duration)


def test_a_section_named_without_a_newer_setting_runs_it_at_its_default(tmp_path):
    """Defaults are the defaults: a file naming rhs: and learner: sections without the
    settings added to them since (rhs.adoption, learner.model, the identifier's anchor)
    runs those at today's defaults, as a file without the sections would; a tag the
    section does not take is refused; a file of an older layout loads at today's
    defaults with a note naming each setting whose default is not what its release
    ran."""
    from dacph_drake.assembly.scenario_files import PlanarLayoutV1
    path = tmp_path / "sections.yaml"
    path.write_text("rhs: {Td: 2.0}\nlearner: {window: 400}\ninertia: {start: 0.2}\n")
    named, bare = load_scenario(path), Scenario()
    assert named.rhs.adoption == bare.rhs.adoption == "certified_set"
    assert named.learner.model == bare.learner.model == "local_bayes"
    assert named.inertia == bare.inertia
    path.write_text("learner: !LocalBayes {}\n")
    with pytest.raises(ConfigError, match=r"learner has the tag !LocalBayes, which this "
                                          r"section does not take"):
        load_scenario(path)
    old = yaml_dump_typed(PlanarLayoutV1.From(BUILT_IN_SCENARIOS["short"]()))
    old = old.replace("  model: local_bayes\n", "").replace("  adoption: certified_set\n", "")
    path.write_text(old)
    import logging
    records = []
    handler = logging.Handler()
    handler.emit = records.append
    logging.getLogger("dacph_drake.assembly.scenario_files").addHandler(handler)
    try:
        loaded = load_scenario(path)
    finally:
        logging.getLogger("dacph_drake.assembly.scenario_files").removeHandler(handler)
    assert loaded.learner.model == "local_bayes" and loaded.rhs.adoption == "certified_set"
    notes = " ".join(record.getMessage() for record in records)
    assert "learner.model = 'local_bayes' (before it existed: 'network')" in notes
    assert "rhs.adoption = 'certified_set' (before it existed: 'trust_band')" in notes


def test_a_run_saved_before_the_model_error_was_measured_keeps_its_meaning():
    """A short DAC run saved by the release before the LHS model error was measured
    (tests/data: its scenario.yaml and run record, the bayes section written at the
    defaults of then, model_error 0.1; no inertia tolerances): read as a saved run, it
    keeps its fingerprint and its settings, while the same file as an input runs
    today's inertia settings."""
    import json
    from dacph_drake.loop.run_store import require_run_of
    from dacph_drake.assembly.scenario_files import load_saved_scenario
    folder = Path(__file__).resolve().parent / "data" / "short_run_before_measured_error"
    meta = json.loads((folder / "run_dac.json").read_text())
    saved = load_saved_scenario(folder / "scenario.yaml")
    require_run_of(saved, meta, folder, "dac")
    assert saved.learner.bayes.model_error == 0.1
    assert saved.inertia == load_scenario(folder / "scenario.yaml").inertia


def test_a_described_run_saved_before_joint_friction_keeps_its_meaning(tmp_path):
    """robot.joint_friction was added at the behaviour before it ("zero"): a saved
    described-arm run's file without the line loads with it at "zero", and its line at
    that value is left out of the fingerprinted text (a run saved before keeps its
    fingerprint); "keep" changes the fingerprint."""
    import copy
    from dacph_drake.assembly.scenario_files import (load_saved_scenario, saved_forms, save_scenario)
    from dacph_drake.loop.run_store import scenario_fingerprint
    scenario = load_scenario("satellite_3dof")
    save_scenario(scenario, tmp_path / "scenario.yaml")
    text = (tmp_path / "scenario.yaml").read_text()
    assert "  joint_friction: zero\n" in text
    (tmp_path / "before.yaml").write_text(text.replace("  joint_friction: zero\n", ""))
    before = load_saved_scenario(tmp_path / "before.yaml")
    assert before.robot.joint_friction == "zero" and before == scenario
    assert "joint_friction" not in saved_forms(scenario)[0]
    kept = copy.deepcopy(scenario)
    kept.robot.joint_friction = "keep"
    assert scenario_fingerprint(kept) != scenario_fingerprint(scenario)

"""A batch of trials is one diagram (loop.simulate.simulate_batch): every trial's
run equals its solo run bit for bit, a trial that diverges stops alone, and the
trials of one batch share the settings that shape the diagram."""
import copy

import numpy as np
import pytest

from dacph_drake.scenario.errors import ConfigError
from dacph_drake.log_layout import LearnerLog
from dacph_drake.loop.simulate import simulate, simulate_batch
from dacph_drake.scenario.built_in import short_scenario


def _trials(count: int, diverging: int = None):
    """``count`` variants of the short scenario, each with its own true link masses,
    true RHS, disturbance, q0 and seed; trial ``diverging`` with actuators 100x
    stronger than its controller assumes (it runs away within milliseconds)."""
    rng = np.random.default_rng(7)
    trials = []
    for i in range(count):
        scenario = copy.deepcopy(short_scenario())
        for link in scenario.robot.truth.links:
            link.mass *= rng.uniform(0.85, 1.15)
        scenario.uncertainty.D_offset = [d * rng.uniform(0.5, 1.5)
                                         for d in scenario.uncertainty.D_offset]
        scenario.disturbance.scale *= rng.uniform(0.5, 2.0)
        scenario.q0 = [0.2 + 0.05 * i, 1.1 - 0.05 * i]
        scenario.seed = 100 + i
        trials.append(scenario)
    if diverging is not None:
        trials[diverging].uncertainty.B_scale = [100.0, 100.0]
    return trials


def _batch_equal_to_solo_runs(trials, controller: str, duration: float):
    """The batch's results, each trial's status, reason, final time and every log
    asserted equal to its solo run's, bit for bit."""
    batch = simulate_batch(trials, controller, duration=duration)
    for scenario, result in zip(trials, batch):
        solo = simulate(scenario, controller, duration=duration)
        assert (result.status, result.reason, result.final_time) == (
            solo.status, solo.reason, solo.final_time)
        assert set(result.logs) == set(solo.logs)
        for name, log in solo.logs.items():
            np.testing.assert_array_equal(result.logs[name], log, err_msg=name)
    return batch


@pytest.mark.parametrize("controller", ["dac", "model-based"])
def test_every_trial_of_a_batch_is_its_solo_run(controller):
    """A batch of 4 trials (different robots, RHS, disturbances, q0 and seeds; trial
    2 diverges) through every system of the loop: each trial's status, reason,
    final time and every log equal its solo run's, bit for bit; the diverging
    trial stopped alone, at the integrator stage where its rate ran away."""
    trials = _trials(4, diverging=2)
    duration = 1.2
    batch = _batch_equal_to_solo_runs(trials, controller, duration)
    assert batch[2].status == "diverged" and "runaway" in batch[2].reason
    assert batch[2].final_time < 0.05
    assert all(result.status == "ok" and result.final_time == pytest.approx(duration)
               for trial, result in enumerate(batch) if trial != 2)


def test_a_learning_trial_is_its_solo_run_through_every_phase():
    """Past the learner's fits, restarts and adoptions (phases of 0.5 + 1 + 1 + 1 s,
    actuators off their prior, one with a fault), each DAC trial of a batch of
    different scenarios equals its solo run, every log bit for bit."""
    from dacph_drake.scenario import ActuatorFault, Phases
    trials = _trials(3)
    for scenario, scale in zip(trials, ([1.0, 1.0], [2.5, 0.6], [0.5, 1.8])):
        scenario.phases = Phases(warmup=0.5, linear=1.0, nonlinear=1.0, disturbance=1.0)
        scenario.uncertainty.B_scale = scale
    trials[1].uncertainty.faults = [ActuatorFault(time=2.2, joint=2, gain=0.5)]
    batch = _batch_equal_to_solo_runs(trials, "dac", trials[0].duration)
    assert all(result.status == "ok" for result in batch)
    published = LearnerLog().network_published
    learned = [np.any(r.logs["learner_log"][:, published] > 0.5) for r in batch]
    assert any(learned), "no trial published a learned quantity"


def test_the_trials_of_a_batch_share_what_shapes_the_diagram(tmp_path):
    """A trial whose periods differ from trial 0's is refused in one line naming
    the setting; so is a batch of described arms whose kinematic trees differ."""
    from dacph_drake.assembly.scenario_files import load_scenario
    trials = _trials(2)
    trials[1].periods.lhs = 2e-3
    with pytest.raises(ConfigError, match="trial 1's periods differs"):
        simulate_batch(trials, "dac", duration=0.01)
    from dacph_drake.robots.description import robot_description
    three = load_scenario("satellite_3dof")
    branched = copy.deepcopy(three)           # joint 3 on link 1, not on link 2
    urdf = robot_description("satellite_3dof").read_text()
    path = tmp_path / "branched.urdf"
    path.write_text(urdf.replace('<parent link="link2"/>\n    <child link="link3"/>',
                                 '<parent link="link1"/>\n    <child link="link3"/>'))
    branched.robot.description = str(path)
    with pytest.raises(ConfigError, match="trial 1's robot differs from trial 0's in "
                                          "its kinematic tree"):
        simulate_batch([three, branched], "dac", duration=0.01)


@pytest.mark.parametrize("controller", ["dac", "model-based"])
def test_every_trial_of_a_spatial_batch_is_its_solo_run(controller):
    """A batch of 3 satellite_3dof trials (their own q0, disturbance, seed and
    actuators; trial 1's made to run away) in one plant of cloned arms
    (plant.AddClonedArms): each trial's status, reason, final time and every log
    equal its solo run's (on the parsed plant) bit for bit."""
    from dacph_drake.assembly.scenario_files import load_scenario
    trials = []
    for i in range(3):
        scenario = load_scenario("satellite_3dof")
        scenario.seed = 10 + i
        scenario.q0 = list(np.asarray(scenario.q0, float) + 0.03 * i)
        scenario.disturbance.scale *= 1 + 0.3 * i
        trials.append(scenario)
    trials[1].uncertainty.B_scale = [100.0] * 3
    batch = _batch_equal_to_solo_runs(trials, controller, duration=0.6)
    assert [result.status for result in batch] == ["ok", "diverged", "ok"]


def test_a_trial_that_breaks_the_step_stops_alone():
    """A trial whose true arm is 1000x lighter than its controller's model, with
    actuators 100x stronger, runs away within a step and its state blows up before
    the monitor's next check: Drake's integrator fails the batch's step. The batch
    goes back to the last check, stops that trial there and takes the step again
    (loop.simulate.advance_in_chunks' recover): the other trials run to the end,
    each bit for bit its solo run; the failing trial keeps its solo run's status,
    reason and stop time."""
    trials = _trials(3)
    for link in trials[1].robot.truth.links:
        link.mass *= 1e-3
        link.inertia *= 1e-3
    trials[1].uncertainty.B_scale = [100.0, 100.0]
    duration = 0.3
    batch = simulate_batch(trials, "dac", duration=duration)
    solo = simulate(trials[1], "dac", duration=duration)
    assert (batch[1].status, batch[1].reason, batch[1].final_time) == (
        solo.status, solo.reason, solo.final_time)
    assert batch[1].status == "diverged" and "runaway" in batch[1].reason
    healthy = [trials[0], trials[2]]
    for scenario, result in zip(healthy, (batch[0], batch[2])):
        alone = simulate(scenario, "dac", duration=duration)
        assert result.status == alone.status == "ok"
        for name, log in alone.logs.items():
            np.testing.assert_array_equal(result.logs[name], log, err_msg=name)

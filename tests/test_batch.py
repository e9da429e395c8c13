"""A batch of trials is one diagram (loop.simulate.simulate_batch): every trial's
run equals its solo run bit for bit, a trial that diverges stops alone, and the
trials of one batch share the settings that shape the diagram."""
import copy

import numpy as np
import pytest

from dacph_drake.errors import ConfigError
from dacph_drake.loop.simulate import simulate, simulate_batch
from dacph_drake.scenario import short_scenario


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


@pytest.mark.parametrize("controller", ["dac", "model-based"])
def test_every_trial_of_a_batch_is_its_solo_run(controller):
    """A batch of 4 trials (different robots, RHS, disturbances, q0 and seeds; trial
    2 diverges) through every system of the loop: each trial's status, reason,
    final time and every log equal its solo run's, bit for bit; the diverging
    trial stopped alone, at the integrator stage where its rate ran away."""
    trials = _trials(4, diverging=2)
    duration = 1.2
    batch = simulate_batch(trials, controller, duration=duration)
    for trial, (scenario, result) in enumerate(zip(trials, batch)):
        solo = simulate(scenario, controller, duration=duration)
        assert (result.status, result.reason, result.final_time) == (
            solo.status, solo.reason, solo.final_time)
        assert set(result.logs) == set(solo.logs)
        for name, log in solo.logs.items():
            np.testing.assert_array_equal(result.logs[name], log, err_msg=name)
    assert batch[2].status == "diverged" and "runaway" in batch[2].reason
    assert batch[2].final_time < 0.05
    assert all(result.status == "ok" and result.final_time == pytest.approx(duration)
               for trial, result in enumerate(batch) if trial != 2)


def test_the_trials_of_a_batch_share_what_shapes_the_diagram():
    """A trial whose periods differ from trial 0's is refused in one line naming
    the setting; so is a batch of described arms (not batched yet)."""
    from dacph_drake.scenario_files import load_scenario
    trials = _trials(2)
    trials[1].periods.lhs = 2e-3
    with pytest.raises(ConfigError, match="trial 1's periods differs"):
        simulate_batch(trials, "dac", duration=0.01)
    spatial = load_scenario("satellite_3dof")
    with pytest.raises(ConfigError, match="batch_size 1"):
        simulate_batch([spatial, copy.deepcopy(spatial)], "dac", duration=0.01)

"""Each axis grows by one module and one registration line: a robot kind
(assembly.registry.register_robot), a task (tasks.registry.register, in
test_tasks.py) and a learner (learning.register_learner), each run through every
command and a sweep (every_command.runs_in_every_command)."""
import copy
from dataclasses import dataclass, replace

import numpy as np
import pytest

from dacph_drake.assembly import registry
from dacph_drake.assembly.registry import register_robot
from dacph_drake.learning import LEARNERS, register_learner
from dacph_drake.learning.local_bayes import LocalBayesLearner
from dacph_drake.log_layout import LearnerLog
from dacph_drake.robots.planar import PlanarRobot
from dacph_drake.scenario import PlanarArm, Scenario
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.scenario.planar_arm import BaseParams, LinkParams, RobotParams
from every_command import TINY_PHASES, runs_in_every_command


# --- A robot kind of one's own, in one module -------------------------------------

@dataclass
class ChainArm:
    """robot: !ChainArm, a planar chain of equal uniform links on a square base.

    Attributes:
        links: The number of links.
        length: Each link's length [m].
        mass: Each link's mass [kg].
        base_mass: The base's mass [kg]."""
    links: int = 3
    length: float = 0.3
    mass: float = 1.0
    base_mass: float = 5.0


def chain_as_planar_arm(section: ChainArm) -> PlanarArm:
    """The planar arm a ChainArm is (its model the truth).

    Args:
        section: The robot section."""
    link = LinkParams(mass=section.mass, length=section.length, com=section.length / 2,
                      inertia=section.mass * section.length**2 / 12)
    base = BaseParams(mass=section.base_mass,
                      inertia=section.base_mass * BaseParams().size**2 / 6)
    truth = RobotParams(base=base, links=[copy.deepcopy(link)
                                          for _ in range(section.links)])
    return PlanarArm(truth=truth, nominal=copy.deepcopy(truth))


class ChainArmRobot(PlanarRobot):
    """The Robot of a ChainArm: the planar robot of the arm it is."""
    TRUTH_SAMPLES = ()

    def __init__(self, scenario: Scenario, task: object):
        super().__init__(replace(scenario, robot=chain_as_planar_arm(scenario.robot)),
                         task)

    @staticmethod
    def SizedScenario(section, q0, task, rows):
        return PlanarRobot.SizedScenario(chain_as_planar_arm(section), q0, task, rows)

    @staticmethod
    def ApplyTruthSample(section, sampled):
        """Nothing to sample (TRUTH_SAMPLES is empty)."""

    @staticmethod
    def ApplyModelError(section, links, base):
        if links is not None or base is not None:
            raise ConfigError("distributions.nominal_*: a ChainArm's model is its "
                              "truth; allowed: none")


@pytest.fixture
def chain_arm_registered(monkeypatch):
    """register_robot(ChainArm, ChainArmRobot), undone after the test."""
    field_ = Scenario.__dataclass_fields__["robot"]
    monkeypatch.setattr(field_, "type", field_.type)
    monkeypatch.setitem(registry.ROBOTS, ChainArm, None)
    register_robot(ChainArm, ChainArmRobot)


def test_a_new_robot_kind_is_one_module_and_one_registration(chain_arm_registered,
                                                             tmp_path):
    """register_robot and nothing else: a file naming ``robot: !ChainArm`` loads sized
    to its arm, serves the planar task (its kind derives from PlanarRobot) and runs
    in every command and a sweep."""
    from dacph_drake.assembly.registry import robot_of
    from dacph_drake.assembly.scenario_files import load_scenario
    path = tmp_path / "chain.yaml"
    path.write_text("robot: !ChainArm {links: 3, length: 0.25}\n" + TINY_PHASES)
    scenario = load_scenario(path)
    assert isinstance(scenario.robot, ChainArm) and len(scenario.q0) == 3
    assert len(scenario.uncertainty.B0) == 3          # sized to its three joints
    assert robot_of(scenario).num_joints == 3
    out = runs_in_every_command(tmp_path, path)
    assert np.load(out / "logs_dac.npz")["u"].shape[1] == 3


# --- A learner of one's own, in one module -----------------------------------------

class PriorLearner(LocalBayesLearner):
    """A learner that publishes the prior (B0, D0) with its range at every update."""

    def Update(self, t, rows, state, model_changed, learning):
        return super().Update(t, rows, state, model_changed, learning=False)


@pytest.fixture
def prior_learner_registered(monkeypatch):
    """register_learner("prior", PriorLearner), undone after the test."""
    monkeypatch.setitem(LEARNERS, "prior", None)
    register_learner("prior", PriorLearner)


def test_a_new_learner_is_one_module_and_one_registration(prior_learner_registered,
                                                          tmp_path):
    """register_learner and nothing else: ``learner.model: prior`` runs in every
    command and a sweep, and what it publishes is the prior throughout."""
    path = tmp_path / "prior.yaml"
    path.write_text("learner: {model: prior}\n" + TINY_PHASES)
    out = runs_in_every_command(tmp_path, path)
    logs = np.load(out / "logs_dac.npz")
    updated = logs["time"] >= 0.1
    assert np.all(logs["learner_log"][updated, LearnerLog().undetermined] == 1.0)


def test_an_unregistered_learner_is_named(tmp_path):
    """A learner.model no registration names is one ConfigError listing the
    registered ones."""
    from dacph_drake.assembly.scenario_files import load_scenario
    (tmp_path / "s.yaml").write_text("learner: {model: prior}\n")
    with pytest.raises(ConfigError, match="learner.model = 'prior'; allowed: "
                                          "local_bayes, network"):
        load_scenario(tmp_path / "s.yaml")

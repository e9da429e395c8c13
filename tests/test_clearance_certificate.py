"""The clearance potential's certificate (robots/clearance_potential.py): a call it
answers without a SceneGraph query returns what the query would, and the joints'
reach bounds the change of every link-base distance."""
import numpy as np
import pytest

from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.robots import clearance_potential
from dacph_drake.robots.description import ParsedDescription
from dacph_drake.assembly.scenario_files import load_scenario


@pytest.fixture(scope="module", params=["satellite_6dof", "satellite_3dof"])
def robot(request):
    scenario = load_scenario(request.param)
    parsed = ParsedDescription(scenario.robot)
    model = FloatingBaseModel(parsed.plant)

    def potential(**kwargs):
        return clearance_potential.BaseClearancePotential(
            parsed=parsed, model=model, gain=1.0,
            margin=scenario.robot.potential.margin, **kwargs)
    return potential, model.num_joints, scenario.robot.potential.margin


def test_a_certified_answer_is_the_query_s(robot):
    """Along random motions, every call of one potential (certifying) equals the
    same call of a potential that always queries as far as asked, bit for bit; the
    certificate answers a share of them, and a share of the queries look only as
    far as the nearest distance's upper bound."""
    potential, n, margin = robot
    certified, queried = potential(), potential()
    rng = np.random.default_rng(3)
    answered, bounded = 0, 0
    for _ in range(10):
        q, w = rng.uniform(-2.5, 2.5, n), rng.normal(0.0, 1.0, n)
        for _ in range(60):
            q = q + 0.002 * w
            for distance in (margin + 0.01, None):
                known = certified._known_q
                at_most = certified._NearestAtMost(q)
                a = certified.Evaluate(q, None, query_distance=distance)
                answered += certified._known_q is known
                bounded += (certified._known_q is not known
                            and at_most < (distance or 1.0))
                queried._known_q = None
                b = queried.Evaluate(q, None, query_distance=distance)
                assert a.U == b.U and a.min_distance == b.min_distance
                np.testing.assert_array_equal(a.gradient, b.gradient)
    assert answered > 50 and bounded > 50


def test_the_reach_bounds_every_distance_change(robot):
    """|d(q2) - d(q1)| <= reach . |q2 - q1| for the nearest link-base distance d at
    random nearby configurations."""
    potential, n, _ = robot
    full = potential(query_distance=10.0)
    rng = np.random.default_rng(4)
    checked = 0
    for _ in range(400):
        q1 = rng.uniform(-3.0, 3.0, n)
        q2 = q1 + rng.normal(0.0, 0.05, n)
        distances = []
        for q in (q1, q2):
            full._known_q = None
            distances.append(full.Evaluate(q, None).min_distance)
        if np.all(np.isfinite(distances)):
            checked += 1
            assert abs(distances[1] - distances[0]) <= full._reach @ np.abs(q2 - q1)
    assert checked > 300

"""The RHS loop: gain rule, DIC check, and the decay rate of e_tau."""
import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from dacph_drake.gain_rule import c_lower_bound, integral_gains, within_trust
from dacph_drake.log_layout import RhsState
from dacph_drake.learning.network import ExportedNetwork, RhsNetwork
from dacph_drake.dynamics.plant import FixStateInputs, MakeArmPlant
from dacph_drake.dynamics.reduced_model import ReducedOrderModel
from dacph_drake.scenario import Rhs, Scenario
from dacph_drake.systems.rhs_integrator import RhsIntegrator, RhsTrial


def test_c_lower_bound_matches_spec():
    # SPEC section 5: inf lambda_min(M) ~ 0.0051 gives c ~ 800 1/s with T_d = 2.
    assert c_lower_bound(2.0, 0.5, 0.0051, 1.0) == pytest.approx(784.3, rel=1e-3)
    assert c_lower_bound(2.0, 0.5, 0.0051, np.e**5) == pytest.approx(2 * 784.3, rel=1e-3)


def test_integral_gains_and_dic():
    k, lam, ok = integral_gains(np.array([[2.0, 0.1], [0.0, 0.5]]), 800.0)
    assert ok and np.allclose(lam.real, [2.0, 0.5]) and np.allclose(k, [400.0, 1600.0])
    assert not integral_gains(np.array([[1.0, 1.0], [1.0, 1.0]]), 800.0)[2]   # singular
    assert not integral_gains(np.diag([1.0, -0.5]), 800.0)[2]                  # Re < 0


def test_trust_band_bounds_the_discrete_loop_gain():
    nominal = np.array([1.0, 1.0])
    assert within_trust(np.array([0.6, 1.9]), nominal, 2.0)
    assert not within_trust(np.array([0.4, 1.0]), nominal, 2.0)     # too small
    assert not within_trust(np.array([1.0, 2.1]), nominal, 2.0)     # too large


def _Integrator(B_hat_scale):
    """An RhsIntegrator whose learner publishes B_hat = B_hat_scale I."""
    model = ReducedOrderModel(MakeArmPlant(Scenario().robot.nominal))
    network = ExportedNetwork(2, [16, 8], 0.01)
    weights = RhsNetwork(2, [16, 8], B_hat_scale * np.eye(2), [0.1, 0.1], 0.01,
                         0).export()
    rhs = RhsIntegrator(trials=[RhsTrial(model=model, network=network, Kd_max=0.5,
                                         lambda_min_M=0.005093, B0=[1.0, 1.0],
                                         D0=[0.1, 0.1])],
                        settings=Rhs(), period=2.5e-4, model_period=1e-2)
    context = rhs.CreateDefaultContext()
    FixStateInputs(rhs, context, np.zeros(10))
    rhs.GetInputPort("weights").FixValue(context, weights)
    rhs.GetInputPort("beta_hat").FixValue(context, [1.0])
    for name in ("tau_request", "tau_observed"):
        rhs.GetInputPort(name).FixValue(context, np.zeros(2))
    return rhs, context


@pytest.mark.parametrize("scale, accepted", [(1.5, True), (0.1, False), (-1.0, False)])
def test_integrator_rejects_estimates_outside_dic_or_trust(scale, accepted):
    """A learned B_hat = 0.1 I (within DIC, outside the trust band) or -I (DIC
    violation) leaves B_hat^-1 and K as they were; 1.5 I is adopted."""
    rhs, context = _Integrator(scale)
    n, L = 2, RhsState(2)
    before = rhs.GetModelGroup(context)
    Simulator(rhs, context).AdvanceTo(1e-4)          # the model refresh at t = 0
    after = rhs.GetModelGroup(context)
    B_inverse, K = after[L.B_inverse].reshape(n, n), after[L.K]
    dic_ok, trusted = after[L.dic_ok], after[L.trusted]
    c = after[L.c]
    assert trusted == float(accepted) and dic_ok == float(scale > 0)
    expected_B_inverse = np.eye(n) / scale if accepted else before[L.B_inverse].reshape(n, n)
    assert np.allclose(B_inverse, expected_B_inverse)
    assert np.allclose(K, c / (scale if accepted else 1.0))


@pytest.mark.parametrize("B_true", [np.eye(2), np.array([[1.2, 0.1], [-0.05, 0.8]])])
def test_e_tau_decays_at_the_rate_the_gain_rule_asks(B_true):
    """A step in tau_c^r through tau = B~ u, observed one sample late, decays in the
    integrator's discrete loop at least as fast as c_min (eq. 48) asks."""
    scenario = Scenario()
    model = ReducedOrderModel(MakeArmPlant(scenario.robot.nominal))
    network = ExportedNetwork(2, [16, 8], 0.01)
    weights = RhsNetwork(2, [16, 8], np.eye(2), [0.1, 0.1], 0.01, 0).export()
    h = scenario.periods.rhs
    lambda_min = 0.005093
    rhs = RhsIntegrator(trials=[RhsTrial(model=model, network=network, Kd_max=0.5,
                                         lambda_min_M=lambda_min, B0=[1.0, 1.0],
                                         D0=[0.1, 0.1])],
                        settings=Rhs(), period=h, model_period=1e-2)
    context = rhs.CreateDefaultContext()
    FixStateInputs(rhs, context, np.zeros(10))
    rhs.GetInputPort("weights").FixValue(context, weights)
    rhs.GetInputPort("beta_hat").FixValue(context, [1.0])
    tau_request = np.array([0.05, -0.03])
    rhs.GetInputPort("tau_request").FixValue(context, tau_request)
    u_history = [np.zeros(2), np.zeros(2)]
    errors = []
    simulator = Simulator(rhs, context)
    for k in range(60):          # one integrator sample (at t = k h) per step
        observed = B_true @ u_history[-2]
        rhs.GetInputPort("tau_observed").FixValue(context, observed)
        errors.append(np.linalg.norm(tau_request - observed))
        simulator.AdvanceTo((k + 0.5) * h)
        u_history.append(rhs.GetOutputPort("u").Eval(context).copy())
    errors = np.array(errors)
    assert errors[-1] < 1e-6 * errors[0]
    rate = -np.log(errors[-1] / errors[-21]) / (20 * h)        # asymptotic decay rate
    c_min = c_lower_bound(2.0, 0.5, lambda_min, 1.0)
    print(f"e_tau decay rate {rate:.0f} 1/s, gain rule asks >= {c_min:.0f} 1/s")
    assert rate >= c_min


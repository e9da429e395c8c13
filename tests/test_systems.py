"""Each LeafSystem alone, with FixValue inputs, against its equation."""
import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from dacph_drake.dynamics.plant import FixStateInputs, MakeArmPlant
from dacph_drake.dynamics.base_repulsion import BaseRepulsionPotential
from dacph_drake.dynamics.reduced_model import ReducedOrderModel
from dacph_drake.dynamics.reference import OrientationReference
from dacph_drake.scenario import Disturbance, Scenario
from dacph_drake.systems.disturbance import DisturbanceSource
from dacph_drake.systems.lhs_controller import LhsController, LhsTrial
from dacph_drake.systems.model_based_inverter import ModelBasedInverter
from dacph_drake.systems.port_observer import PortObserver
from dacph_drake.systems.true_rhs import TrueRhs



@pytest.fixture(scope="module")
def model():
    return ReducedOrderModel(MakeArmPlant(Scenario().robot.nominal))


def _state(q, qdot, model):
    v_base = model.BaseVelocity(np.concatenate([[0, 0, 0], q]), qdot)
    return np.concatenate([[0, 0, 0], q, v_base, qdot])


def test_disturbance_source_hand_values():
    source = DisturbanceSource(settings=[Disturbance()], starts=[10.0])
    context = source.CreateDefaultContext()
    context.SetTime(9.99)
    assert np.all(source.GetOutputPort("disturbance").Eval(context) == 0)
    context.SetTime(12.5)
    t = 12.5
    expected = (np.array([0.03, -0.02])
                + 0.02 * np.array([np.sin(2 * np.pi * 0.05 * t), np.cos(2 * np.pi * 0.07 * t)])
                + 0.005 * np.sin(2 * np.pi * 20 * t) * np.array([1, -1]))
    np.testing.assert_allclose(source.GetOutputPort("disturbance").Eval(context), expected, atol=1e-15)


def test_true_rhs_by_phase(model):
    scenario = Scenario()
    truth = TrueRhs(plant=MakeArmPlant(scenario.robot.truth),
                    truths=[scenario.robot.truth], uncertainties=[scenario.uncertainty],
                    phases=[scenario.phases])
    context = truth.CreateDefaultContext()
    q, qdot = np.array([0.5, -0.2]), np.array([0.1, 0.3])
    u, d = np.array([0.2, -0.1]), np.array([0.01, 0.02])
    FixStateInputs(truth, context, _state(q, qdot, model))
    truth.GetInputPort("u").FixValue(context, u)
    constant = DisturbanceSource(settings=[Disturbance(
        lf_offset=list(d), lf_amplitude=[0.0, 0.0], hf_amplitude=0.0)], starts=[0.0])
    truth.GetInputPort("disturbance_model").FixValue(
        context, constant.GetOutputPort("disturbance_model").Eval(
            constant.CreateDefaultContext()))
    tau = truth.GetOutputPort("tau")
    context.SetTime(1.0)                                    # warm-up: B0 = I, D0 = 0.1 I
    np.testing.assert_allclose(tau.Eval(context), u - 0.1 * qdot + d, atol=1e-15)
    p = model.MassMatrix(q) @ qdot
    context.SetTime(100.0)                                  # linear terms on
    B = np.diag([1 - 0.1 * 0.5, 1 + 0.05 * 0.5 + 0.15 * -0.2])
    D = np.array([0.1 + 0.02 + 0.4 * p[0], 0.1 + 0.05 + 0.4 * p[1]])
    np.testing.assert_allclose(tau.Eval(context), B @ u - D * qdot + d, atol=1e-14)
    context.SetTime(600.0)                                  # plus nonlinear terms
    B += np.diag([0.15 * p[0]**2, -0.25 * p[1]**2]) + np.array([[0, -0.1], [0.4, 0]]) * 0.25
    D += np.array([-0.05 * p[0]**2, 0.1 * p[1]**2])
    np.testing.assert_allclose(tau.Eval(context), B @ u - D * qdot + d, atol=1e-14)
    np.testing.assert_allclose(truth.GetOutputPort("true_matrices").Eval(context),
                               np.concatenate([B.reshape(-1), D]), atol=1e-14)


def test_model_based_inverter():
    inverter = ModelBasedInverter(uncertainties=[Scenario().uncertainty])
    context = inverter.CreateDefaultContext()
    x = np.arange(10) / 10.0
    FixStateInputs(inverter, context, x)
    inverter.GetInputPort("tau_request").FixValue(context, [0.3, -0.4])
    np.testing.assert_allclose(inverter.GetOutputPort("u").Eval(context),
                               np.array([0.3, -0.4]) + 0.1 * x[8:], atol=1e-15)


def _observe(model, q, qdot, qddot, u=None, h=2.5e-4, cutoff=0.0):
    """A PortObserver initialized at rates qdot - h qddot / 2 and sampled once (at
    t = 0, a one-period simulation) at qdot + h qddot / 2, so that qdot is the
    interval's midpoint rate and qddot its backward difference; the reduced model
    [M, C'] at (q, qdot)."""
    observer = PortObserver(num_joints=2, sample_period=h,
                            noise_std=0.0, seeds=[0], anti_alias_cutoff=cutoff)
    context = observer.CreateDefaultContext()
    r = model.Evaluate(q, qdot)
    observer.GetInputPort("reduced_model").FixValue(
        context, np.concatenate([r.M.reshape(-1), r.C.reshape(-1)]))
    if u is not None:
        observer.GetInputPort("u").FixValue(context, u)
    simulator = Simulator(observer, context)
    FixStateInputs(observer, context, _state(q, qdot - 0.5 * h * qddot, model))
    simulator.Initialize()                         # the initialization event
    FixStateInputs(observer, context, _state(q, qdot + 0.5 * h * qddot, model))
    simulator.AdvanceTo(0.5 * h)                   # the sample at t = 0
    return observer, context, r


def test_port_observer(model):
    q, qdot, qddot = np.array([0.4, 0.9]), np.array([0.2, -0.5]), np.array([1.0, -2.0])
    observer, context, r = _observe(model, q, qdot, qddot)
    np.testing.assert_allclose(observer.GetOutputPort("tau_observed").Eval(context),
                               r.M @ qddot + r.C @ qdot, atol=1e-12)


def test_lhs_controller_equation(model):
    scenario = Scenario()
    potential = BaseRepulsionPotential(scenario.robot.nominal, scenario.robot.potential)
    reference = OrientationReference(scenario.task.reference, 1.3)
    lhs = LhsController(trials=[LhsTrial(model=model, potential=potential,
                                         reference=reference)],
                        gains=scenario.task.gains, period=1e-3)
    q, qdot = np.array([1.3, 2.2]), np.array([0.3, -0.2])     # potential active here
    x = _state(q, qdot, model)
    x[2] = 0.1
    t, chi = 3.0, 0.02
    tau, log = lhs.Control(t, x[2], q, qdot, chi)
    # Independent check of nu and s, and of nu_dot by differencing nu along the flow.
    def nu_of(time, qq, qd):
        r = model.Evaluate(qq, qd)
        D = r.D
        Dp = D / (D @ D)
        a_d, ad_d, _ = reference(time)
        alpha = x[2] + np.sum(qq) + (time - t) * r.base_velocity_map[2] @ qdot
        xi = -scenario.task.gains.eta * potential.Evaluate(qq, qd)[1]
        return Dp * (ad_d - scenario.task.gains.Lambda * (alpha - a_d)) \
            + (np.eye(2) - np.outer(Dp, D)) @ xi, D, xi, Dp
    nu, D, xi, Dp = nu_of(t, q, qdot)
    s = qdot - nu
    np.testing.assert_allclose(log[:2], s, atol=1e-14)
    # The null-space term does not change alpha_dot: D (I - D+ D) xi = 0.
    assert abs(D @ ((np.eye(2) - np.outer(Dp, D)) @ xi)) < 1e-15 * np.linalg.norm(xi) * 10
    assert np.linalg.norm(xi) > 1e-3
    h = 1e-6
    qddot = np.array([0.7, -0.4])
    nu_plus = nu_of(t + h, q + h * qdot, qdot + h * qddot)[0]
    nu_minus = nu_of(t - h, q - h * qdot, qdot - h * qddot)[0]
    nu_dot_fd = (nu_plus - nu_minus) / (2 * h)
    r = model.Evaluate(q, qdot)
    expected = (r.M @ nu_dot_fd + r.C @ nu - scenario.task.gains.Kd * s
                - chi * np.tanh(s / scenario.task.gains.epsilon))
    np.testing.assert_allclose(tau, expected, rtol=1e-6, atol=1e-9)


def test_port_observer_sample_is_one_consistent_instant(model):
    """port_sample = [q, M qdot, qdot, u, tau_obs] of the same sample: the u the plant
    received when qddot was measured; with an anti-alias cutoff f the regressed part
    moves by a = 1 - exp(-2 pi f h) of the way towards the new sample."""
    h, f = 2.5e-4, 6.0
    q, qdot, qddot = np.array([0.4, 0.9]), np.array([0.2, -0.5]), np.array([1.0, -2.0])
    u = np.array([0.03, -0.01])
    r = model.Evaluate(q, qdot)
    tau = r.M @ qddot + r.C @ qdot
    for cutoff, a in ((0.0, 1.0), (f, 1 - np.exp(-2 * np.pi * f * h))):
        observer, context, _ = _observe(model, q, qdot, qddot, u, h, cutoff)
        sample = observer.GetOutputPort("port_sample").Eval(context)
        np.testing.assert_allclose(sample[:4], np.concatenate([q, r.M @ qdot]),
                                   atol=1e-15)
        np.testing.assert_allclose(sample[4:], a * np.concatenate([qdot, u, tau]),
                                   atol=1e-12)


def test_regression_filter_is_the_band_pass_cascade():
    from dacph_drake.learning.identification import BandPassCascade
    from dacph_drake.scenario import Learner
    from dacph_drake.systems.regression_filter import RegressionFilter
    settings, h = Learner(), 0.01
    system = RegressionFilter(settings=settings, num_joints=2, period=h)
    context = system.CreateDefaultContext()
    rng = np.random.default_rng(3)
    samples = rng.standard_normal((50, 10))
    outputs = []
    simulator = Simulator(system, context)
    for k, sample in enumerate(samples):          # one filter update (t = k h) a step
        system.GetInputPort("port_sample").FixValue(context, sample)
        simulator.AdvanceTo((k + 0.5) * h)
        outputs.append(system.GetOutputPort("filtered_sample").Eval(context).copy())
    outputs = np.array(outputs)
    expected = BandPassCascade(*settings.band, *settings.band_sections, h).Filter(
        samples[:, 4:])
    np.testing.assert_array_equal(outputs[:, :4], samples[:, :4])     # q, p unfiltered
    np.testing.assert_allclose(outputs[:, 4:], expected, atol=1e-15)


def test_lhs_controller_adds_the_excitation(model):
    from dacph_drake.scenario import Excitation
    scenario = Scenario()
    potential = BaseRepulsionPotential(scenario.robot.nominal, scenario.robot.potential)
    reference = OrientationReference(scenario.task.reference, 1.3)
    excitation = Excitation(amplitude=2e-3, frequencies=[3.0, 5.0])
    trial = LhsTrial(model=model, potential=potential, reference=reference)
    plain = LhsController(trials=[trial], gains=scenario.task.gains, period=1e-3)
    excited = LhsController(trials=[trial], gains=scenario.task.gains, period=1e-3,
                            excitation=excitation)
    x = _state(np.array([0.3, 1.0]), np.array([0.1, -0.1]), model)
    t = 0.37
    q, qdot = x[3:5], x[8:]
    difference = (excited.Control(t, x[2], q, qdot, 0.02)[0]
                  - plain.Control(t, x[2], q, qdot, 0.02)[0])
    np.testing.assert_allclose(
        difference, 2e-3 * np.sin(2 * np.pi * np.array([3.0, 5.0]) * t), atol=1e-17)
    np.testing.assert_allclose(Excitation(frequencies=[2.0, 8.0]).Frequencies(3),
                               [2.0, 4.0, 8.0])


def test_port_observer_on_a_known_trajectory():
    """The ground truth driven by smooth torques (9 and 13 Hz) and d(t): tau_obs(k),
    formed at sample k from the backward difference of the sampled rates, is the true
    port torque at the interval's midpoint (mean of the true RHS output at t_k-1 and
    t_k) - half a sample (0.125 ms) behind the sample instant - to within 0.1 % of
    its size (the LHS's M, C' are up to one LHS period old); compared with the torque
    at the sample instant it is off by the half-sample delay (over 1 %)."""
    from pydrake.systems.framework import DiagramBuilder
    from pydrake.systems.primitives import ConstantVectorSource, LogVectorOutput, Sine
    from dacph_drake.dynamics.plant import STATE_SIGNALS, AddFreeFloatingArm, AddStateSplitter
    from dacph_drake.scenario.simulator import MakeSimulator
    scenario = Scenario()
    h = scenario.periods.rhs
    builder = DiagramBuilder()
    plant, _ = AddFreeFloatingArm(builder, scenario.robot.truth)
    model = ReducedOrderModel(MakeArmPlant(scenario.robot.nominal))
    truth = builder.AddSystem(TrueRhs(plant=plant, truths=[scenario.robot.truth],
                                       uncertainties=[scenario.uncertainty],
                                       phases=[scenario.phases]))
    source = builder.AddSystem(DisturbanceSource(settings=[scenario.disturbance],
                                                 starts=[0.0]))
    u = builder.AddSystem(Sine([0.02, 0.015], [9.0, 13.0], [0.0, 1.0], 2))
    lhs = builder.AddSystem(LhsController(
        trials=[LhsTrial(model=model, potential=BaseRepulsionPotential(
            scenario.robot.nominal, scenario.robot.potential),
            reference=OrientationReference(scenario.task.reference, 1.3))],
        gains=scenario.task.gains, period=scenario.periods.lhs))
    chi = builder.AddSystem(ConstantVectorSource([0.05]))
    builder.Connect(chi.get_output_port(), lhs.GetInputPort("chi"))
    observer = builder.AddSystem(PortObserver(num_joints=2, sample_period=h,
                                              noise_std=0.0, seeds=[0]))
    splitter = AddStateSplitter(builder, plant)
    builder.Connect(u.get_output_port(0), truth.GetInputPort("u"))
    builder.Connect(source.GetOutputPort("disturbance_model"),
                    truth.GetInputPort("disturbance_model"))
    builder.Connect(truth.GetOutputPort("tau"), plant.get_actuation_input_port())
    builder.Connect(plant.get_state_output_port(), truth.GetInputPort("state"))
    for system in (lhs, observer):
        for signal in STATE_SIGNALS:
            if system.HasInputPort(signal):
                builder.Connect(splitter.GetOutputPort(signal), system.GetInputPort(signal))
    builder.Connect(lhs.GetOutputPort("reduced_model"), observer.GetInputPort("reduced_model"))
    true_log = LogVectorOutput(truth.GetOutputPort("tau"), builder, h)
    observed_log = LogVectorOutput(observer.GetOutputPort("tau_observed"), builder, h)
    diagram = builder.Build()
    simulator = MakeSimulator(diagram, scenario.simulator)
    context = simulator.get_mutable_context()
    plant.SetPositions(plant.GetMyContextFromRoot(context), [0, 0, 0, *scenario.q0])
    simulator.AdvanceTo(1.0)
    true_tau = true_log.FindLog(context).data().T
    observed = observed_log.FindLog(context).data().T
    # A logger publishes at t_k before the updates at t_k: its tau_observed at t_k was
    # formed at t_k-1, for the interval [t_k-2, t_k-1].
    midpoint = 0.5 * (true_tau[2:-1] + true_tau[1:-2])
    size = np.max(np.linalg.norm(midpoint, axis=1))
    error = np.max(np.linalg.norm(observed[3:] - midpoint, axis=1)) / size
    at_sample = np.max(np.linalg.norm(observed[3:] - true_tau[2:-1], axis=1)) / size
    print(f"max |tau_obs - tau(mid)| / max |tau| = {error:.2e}; against the torque at "
          f"the sample instant instead: {at_sample:.2e}")
    assert error < 1e-3 < at_sample

"""Verification checks (dacph verify): each one fails on a deliberately unstable
case with a clear reason, the short scenario passes them all, and the stress cases
behave as the theory predicts."""
import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, LogVectorOutput

from dacph_drake.analysis.lyapunov_envelope import check_lyapunov_envelope
from dacph_drake.analysis.region_of_attraction import sliding_region_of_attraction
from dacph_drake.analysis.rhs_loop import check_rhs_loop, rhs_loop_system
from dacph_drake.loop.verify import verify_logs, verify_run
from dacph_drake.app.cli import main
from dacph_drake.dynamics.plant import MakeArmPlant
from dacph_drake.dynamics.reduced_model import ReducedOrderModel
from dacph_drake.scenario.planar_arm import RobotParams
from dacph_drake.loop.simulate import simulate
from dacph_drake.scenario import Phases, Stress
from dacph_drake.scenario.built_in import short_scenario

H, LAMBDA_LHS, TD = 2.5e-4, 196.35, 2.0


def test_rhs_loop_system_reproduces_the_integrator_with_a_delayed_observer():
    """The LinearSystem's e_tau step response equals the recursion the RhsIntegrator
    runs against a one-sample-late observer (tests/test_rhs_loop.py)."""
    B, K = np.array([[1.2, 0.1], [-0.05, 0.8]]), np.array([700.0, 1100.0])
    tau_request = np.array([0.05, -0.03])
    builder = DiagramBuilder()
    loop = builder.AddSystem(rhs_loop_system(B, K, H))
    source = builder.AddSystem(ConstantVectorSource(tau_request))
    builder.Connect(source.get_output_port(), loop.get_input_port())
    logger = LogVectorOutput(loop.get_output_port(), builder, H)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(30 * H)
    e_drake = logger.FindLog(simulator.get_context()).data().T[:30]
    u_I, previous, e_recursion = np.zeros(2), np.zeros(2), []
    for _ in range(30):
        observed = B @ previous
        e = tau_request - observed
        e_recursion.append(e)
        previous = u_I.copy()
        u_I = u_I + H * K * e
    np.testing.assert_allclose(e_drake, np.array(e_recursion), atol=1e-15)


def test_rhs_loop_check_passes_the_nominal_loop():
    check = check_rhs_loop(np.eye(2), np.array([900.0, 900.0]), H, LAMBDA_LHS, TD)
    assert check.ok and check.margin > 0.3 and check.lyapunov_P_min_eigenvalue > 0
    assert check.lyapunov_residual < 1e-12 and check.decay_rate > 900.0


@pytest.mark.parametrize("B, K, h, reason", [
    (np.eye(2), [900.0, 900.0], 1.5e-3, "spectral radius"),           # RHS period too slow
    (np.eye(2), [-900.0, 900.0], H, "spectral radius"),                # wrong-signed gain
    (np.array([[1.0, 1.0], [1.0, 1.0]]), [900.0, 900.0], H, "DIC"),    # singular B_hat
    (np.eye(2), [300.0, 300.0], H, "time-scale separation"),          # c below eq. 45
])
def test_rhs_loop_check_fails_unstable_cases_with_a_reason(B, K, h, reason):
    check = check_rhs_loop(np.asarray(B), np.asarray(K), h, LAMBDA_LHS, TD)
    assert not check.ok and reason in check.reason


def _envelope(V, t):
    n = len(t)
    return check_lyapunov_envelope(t, V, np.zeros(n), np.full(n, 1e-3), 0.5, 0.5,
                                   0.005093, 0.04442, 0.2, 2)


def test_envelope_accepts_decay_between_the_rates_and_rejects_growth():
    t = np.arange(0, 1, 0.01)
    r_slow = 2 * 0.5 / 0.04442
    assert _envelope(1e-2 * np.exp(-2 * r_slow * t), t).ok          # inside
    growing = _envelope(1e-2 * np.exp(+5.0 * t), t)                  # V grows
    assert not growing.ok and "envelope" in growing.reason
    too_fast = _envelope(1e-2 * np.exp(-5000.0 * t) + 1e-30, t)      # beyond r_low
    assert not too_fast.ok


def test_envelope_accounts_for_the_excitation():
    """A V held up by the excitation tau_pe (||tau_pe|| <= a) at its level: the
    envelope without the excitation term rejects it, the one with a admits it, and
    growth is still rejected with it."""
    t = np.arange(0, 1, 0.01)
    n, a, Kd, chi, epsilon = len(t), 2e-4 * np.sqrt(2), 0.5, 1e-3, 0.2
    r_slow = 2 * Kd / 0.04442
    floor = 2 * 2 * 0.2785 * chi * epsilon / r_slow          # above delta / r_slow
    assert floor < (2 * 0.2785 * chi * epsilon + a**2 / (2 * Kd)) / (r_slow / 2)
    V = np.full(n, floor)
    check = lambda V, a: check_lyapunov_envelope(            # noqa: E731
        t, V, np.zeros(n), np.full(n, chi), Kd, Kd, 0.005093, 0.04442, epsilon, 2,
        excitation_norm=a)
    assert not check(V, 0.0).ok and check(V, a).ok
    assert not check(floor * np.exp(5.0 * t), a).ok


def test_region_of_attraction_is_a_real_certificate():
    """Drake's SOS certificate: the polynomial sliding dynamics started on the
    boundary of the certified ball converge; the region shrinks as chi grows
    (the cubic tanh term destabilizes large s)."""
    model = ReducedOrderModel(MakeArmPlant(RobotParams()))
    q = np.array([0.3, 1.0])
    small = sliding_region_of_attraction(model, q, 0.5, 0.01, 0.2)
    large = sliding_region_of_attraction(model, q, 0.5, 0.05, 0.2)
    assert small.radius > large.radius > 0
    M = model.Evaluate(q, np.zeros(2)).M
    Gamma = [model.Evaluate(q, np.eye(2)[k]).C for k in range(2)]
    s = 0.999 * large.radius * np.array([0.6, -0.8])
    for _ in range(20000):                    # explicit Euler, 0.1 ms, 2 s
        x = s / 0.2
        force = sum(s[k] * Gamma[k] for k in range(2)) @ s + 0.5 * s \
            + 0.05 * (x - x**3 / 3)
        s = s - 1e-4 * np.linalg.solve(M, force)
    assert np.linalg.norm(s) < 1e-3 * large.radius


def test_short_scenario_passes_every_check(quick_reproduction, tmp_path):
    _, run_dir = quick_reproduction
    report = verify_run(run_dir, tmp_path)
    assert main(["verify", str(run_dir)]) == 0
    failed = {k: v for k, v in report["checks"].items() if not v["ok"]}
    assert report["ok"], failed
    assert report["checks"]["rhs_loop_learned"]["evaluated"] > 100
    assert report["checks"]["lhs_envelope"]["samples_checked"] > 1000
    for name in ("verification.md", "verification.json", "verification.png"):
        assert (tmp_path / name).stat().st_size > 500
    text = (tmp_path / "verification.md").read_text()
    assert "- first_failure_time: none" in text          # a passing run has none
    assert "None" not in text and "nan" not in text


def _stress_run(scale, trust_ratio, out_dir=None):
    scenario = short_scenario()
    scenario.phases = Phases(warmup=0.5, linear=1.0, nonlinear=0.5, disturbance=0.5)
    scenario.stress = Stress(B_hat_scale=scale, start=1.0)
    scenario.rhs.trust_ratio = trust_ratio
    scenario.periods.log = 1e-3
    result = simulate(scenario, "dac", out_dir=out_dir)
    meta = {"status": result.status, "reason": result.reason,
            "final_time": result.final_time}
    return result, verify_logs(result.logs, scenario, meta)


def test_stress_within_the_bound_stays_stable_and_verified():
    """B_hat off by 0.6 (inside the trust band; the discrete loop gain with the true
    B~ becomes h c / 0.6 < 1): stable and every check passes."""
    result, report = _stress_run(0.6, 2.0)
    assert result.status == "ok" and report["ok"], report["checks"]


def test_stress_beyond_the_bound_is_flagged_before_it_diverges(tmp_path):
    """B_hat off by 0.15 with the trust band opened (trust_ratio 10): the loop with
    the true B~ has gain h c / 0.15 > 1. The truth-loop check flags it before the
    divergence monitor stops the run; with the default band the integrator rejects
    the estimate instead and the run stays stable."""
    result, report = _stress_run(0.15, 10.0, tmp_path)
    truth = report["checks"]["rhs_loop_truth"]
    assert result.status == "diverged" and not report["ok"]
    assert 1.0 <= truth["first_failure_time"] < result.final_time
    assert "spectral radius" in truth["first_failure"]
    assert main(["verify", str(tmp_path)]) == 1          # usable in a user's CI
    assert (tmp_path / "verification.md").read_text().startswith("# Verification: FAIL")
    guarded, guarded_report = _stress_run(0.15, 2.0)
    assert guarded.status == "ok" and guarded_report["ok"]
    rejected = guarded_report["estimates_rejected_by_the_integrator"]
    assert 1.0 <= rejected["first_rejection_time"] <= 1.02


def test_a_region_beyond_its_budget_is_skipped_with_the_reason(quick_reproduction,
                                                               tmp_path, capsys):
    """The region of attraction's SOS program runs in a process of its own with a
    wall-time budget (dacph verify --region-budget): one too short for it stops the
    program and reports the check as skipped, saying why, while every other check
    runs; the certificate within budget is the in-process one's."""
    import shutil
    from dacph_drake.analysis.region_of_attraction import _Region
    run_dir = tmp_path / "run"                  # a copy: the session's run stays as is
    shutil.copytree(quick_reproduction[1], run_dir)
    assert main(["verify", str(run_dir), "--region-budget", "0.001"]) == 0
    printed = capsys.readouterr().out
    assert "skipped: the sums-of-squares program for 2 joints did not finish within " \
           "the budget of 0.001 s" in printed and "(1 check skipped)" in printed
    report = verify_run(run_dir, tmp_path, region_budget=0.001)
    region = report["checks"]["region_of_attraction"]
    assert region["ok"] and region["skipped"] and region["radius"] != region["radius"]
    assert report["checks"]["rhs_loop_truth"]["evaluated"] > 100
    model = ReducedOrderModel(MakeArmPlant(RobotParams()))
    q = np.array([0.3, 1.0])
    budgeted = sliding_region_of_attraction(model, q, 0.5, 0.05, 0.2)
    M = model.Evaluate(q, np.zeros(2)).M
    Gamma = [model.Evaluate(q, np.eye(2)[k]).C for k in range(2)]
    assert budgeted == _Region(q, M, Gamma, 0.5 * np.eye(2), 0.05, np.full(2, 5.0))
    assert main(["verify", str(run_dir), "--region-budget", "0"]) == 2


@pytest.mark.parametrize("name", ["short", "sweeps/satellite_3dof_spacecraft.yaml"])
def test_with_noisy_sensors_the_envelope_holds_at_the_true_state(name):
    """The LHS recomputed at the ground truth's logged state (the planar and the spatial
    task): at t = 0, where the LHS initialized on the truth (the sensors pass it until
    they have sampled), it is the LHS's own logged V to round-off; after, V at the true
    state differs from the measured one, and the command's error (the sensors' noise and
    the hold) bounds the envelope's input, inside which V stays. With the sensors off V
    is the LHS's own log."""
    from dacph_drake.assembly.registry import robot_of
    from dacph_drake.assembly.scenario_files import load_scenario
    from dacph_drake.log_layout import AttitudeLog, LhsLog
    from dacph_drake.scenario import Sensing
    from dacph_drake.scenario.built_in import spacecraft_sensing
    scenarios = []
    for sensing in (Sensing(), spacecraft_sensing()):
        scenario = load_scenario(name)
        scenario.phases = Phases(warmup=0.3, linear=0.4, nonlinear=0.4, disturbance=0.4)
        scenario.inertia.fit_tolerance = 0.0
        scenario.sensing = sensing
        scenarios.append(scenario)
    plain, run = (simulate(scenario, "dac") for scenario in scenarios)
    assert run.status == "ok"
    robot = robot_of(scenario)
    column = (LhsLog(robot.num_joints) if robot.task.log_name == "lhs_log"
              else AttitudeLog()).lyapunov_V
    side = robot.task.VerifyLhs(robot, run.logs, 0.0)
    logged = run.logs[robot.task.log_name][:, column]
    assert side.V[0] == pytest.approx(logged[0], rel=1e-9)
    assert not np.allclose(side.V[1:], logged[1:], rtol=1e-3)
    assert side.command_error > 0
    report = verify_logs(run.logs, scenario, {"status": run.status}, None,
                         region_budget=0.0)
    assert report["checks"]["lhs_envelope"]["ok"]
    assert report["settings"]["command_error"] == side.command_error
    off = robot.task.VerifyLhs(robot_of(scenarios[0]), plain.logs, 0.0)
    assert off.command_error == 0.0
    np.testing.assert_array_equal(off.V, plain.logs[robot.task.log_name][:, column])

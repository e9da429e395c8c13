"""The learner's regression on synthetic port data with known answers: the band-pass
keeps the port relation, the regularized learner learns what the data inform and
keeps the prior where they do not, and a disturbance does not make B_hat collapse."""
import numpy as np
import pytest

from dacph_drake.learning.identification import (BandPassCascade, ChangeDetector,
                                                 PortSample, RhsIdentifier)
from dacph_drake.scenario import Learner

H = 0.01                                     # the learner's sample period [s]
B0, D0 = np.eye(2), np.array([0.1, 0.1])


def _multisine(t, amplitudes, frequencies, phase=0.0):
    return sum(a * np.sin(2 * np.pi * f * t + phase + k)
               for k, (a, f) in enumerate(zip(amplitudes, frequencies)))


def _rows(t, q, p, qdot, u, tau, band: bool):
    """Learner rows [t, q, p, qdot, u, tau], the regressed part band-passed with the
    default Learner's filter if ``band``."""
    sample = np.concatenate([q, p, qdot, u, tau], axis=1)
    if band:
        L, settings = PortSample(2), Learner()
        sample[:, L.regressed] = BandPassCascade(
            *settings.band, *settings.band_sections, H).Filter(sample[:, L.regressed])
    return np.concatenate([t[:, None], sample], axis=1)


def _learn(rows, settings: Learner, seed=0, period=0.1):
    """Replays ``rows`` through an RhsIdentifier as the RhsLearner does: every
    ``period`` a fit on the last ``window`` samples."""
    identifier = RhsIdentifier(2, settings, B0, D0, seed)
    every = int(round(period / H))
    for k in range(every, len(rows), every):
        identifier.Fit(rows[max(0, k - settings.window):k], rows[k - 1, 0])
    return identifier


def test_band_pass_keeps_the_port_relation_and_rejects_out_of_band_signals():
    settings = Learner()
    cascade = BandPassCascade(*settings.band, *settings.band_sections, H)
    t = np.arange(0, 20, H)
    in_band = np.sin(2 * np.pi * 3.5 * t)[:, None]
    slow = np.sin(2 * np.pi * 0.07 * t)[:, None]          # d_LF
    fast = np.sin(2 * np.pi * 20.0 * t)[:, None]          # d_HF
    gain = lambda x: np.sqrt(np.mean(cascade.Filter(x)[t > 10] ** 2)) * np.sqrt(2)  # noqa
    assert gain(slow) < 1e-4 * gain(in_band) and gain(fast) < 1e-3 * gain(in_band)
    assert gain(in_band) > 0.1
    # Linear and time-invariant: filter(B u - D qdot) = B filter(u) - D filter(qdot).
    rng = np.random.default_rng(0)
    u, qdot = rng.standard_normal((len(t), 2)), rng.standard_normal((len(t), 2))
    B, D = np.array([[1.2, 0.1], [-0.3, 0.9]]), np.array([0.12, 0.15])
    np.testing.assert_allclose(cascade.Filter(u @ B.T - D * qdot),
                               cascade.Filter(u) @ B.T - D * cascade.Filter(qdot),
                               atol=1e-12)


def _confounded_data(seed=0):
    """u moves along v1 only, up to a tiny independent component along v2; the truth
    differs from B0 along both. qdot is independent (D is informed)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, 30, H)
    v1, v2 = np.array([1.0, 2.0]) / np.sqrt(5), np.array([2.0, -1.0]) / np.sqrt(5)
    a = _multisine(t, [1e-3, 1e-3], [2.7, 4.1])
    e = 1e-6 * rng.standard_normal(len(t))
    u = np.outer(a, v1) + np.outer(e, v2)
    qdot = np.stack([_multisine(t, [3e-3, 2e-3], [3.3, 2.2], 0.5),
                     _multisine(t, [2e-3, 3e-3], [3.9, 2.5], 1.0)], axis=1)
    w = np.array([0.6, -0.8])
    B_true = B0 + 0.25 * np.outer(w, v1) + 0.25 * np.outer(w, v2)
    D_true = np.array([0.13, 0.16])
    tau = u @ B_true.T - D_true * qdot + 2e-7 * rng.standard_normal((len(t), 2))
    q = np.tile([0.3, 1.0], (len(t), 1))
    return t, q, 0.01 * qdot, qdot, u, tau, B_true, D_true, v1, v2


def test_confounded_direction_keeps_the_prior_and_the_informed_one_is_learned():
    """B_hat v1 (informed) converges to B~ v1 and D_hat to D~; B_hat v2 (excited
    1000 times less than v1) stays within 10 % of B0 v2, measured against the
    prior's error along v2, in regularized mode. The paper's plain learner on the
    same data moves B_hat v2 by more than 20 % of that: Adam scales each parameter's
    step by its own gradient history, which is not rotation-invariant, so steps
    along v1 leak into v2, and nothing in the plain loss pulls v2 back."""
    t, q, p, qdot, u, tau, B_true, D_true, v1, v2 = _confounded_data()
    errors = {}
    for mode in ("regularized", "plain"):
        settings = Learner(mode=mode)
        identifier = _learn(_rows(t, q, p, qdot, u, tau, band=mode == "regularized"),
                            settings)
        B, D = identifier.Estimate(q[-1], p[-1])
        errors[mode] = (np.linalg.norm((B - B_true) @ v1), np.linalg.norm((B - B0) @ v2),
                        np.max(np.abs(D - D_true) / D_true))
    prior_error_v1 = np.linalg.norm((B0 - B_true) @ v1)
    informed, moved_uninformed, D_error = errors["regularized"]
    assert informed < 0.05 * prior_error_v1, errors
    prior_error_v2 = np.linalg.norm((B_true - B0) @ v2)
    assert moved_uninformed < 0.1 * prior_error_v2, errors
    assert D_error < 0.05, errors
    assert errors["plain"][1] > 0.2 * prior_error_v2, errors


def test_the_prior_is_what_keeps_the_uninformed_direction():
    """The prior term's ablation on the same data: band-passed and recency-weighted
    alike, the regularized learner with prior_weight = 0 still learns v1 but lets
    B_hat v2 drift by more than 20 % of the prior's error along v2 (with the default
    prior_weight, less than 10 %)."""
    t, q, p, qdot, u, tau, B_true, _, v1, v2 = _confounded_data()
    rows = _rows(t, q, p, qdot, u, tau, band=True)
    prior_error_v2 = np.linalg.norm((B_true - B0) @ v2)
    moved = {}
    for rho in (Learner().prior_weight, 0.0):
        B, _ = _learn(rows, Learner(prior_weight=rho)).Estimate(q[-1], p[-1])
        assert np.linalg.norm((B - B_true) @ v1) < 0.05 * np.linalg.norm(
            (B0 - B_true) @ v1), rho
        moved[rho] = np.linalg.norm((B - B0) @ v2) / prior_error_v2
    assert moved[Learner().prior_weight] < 0.1 and moved[0.0] > 0.2, moved


def _disturbed_closed_loop_data(d_offset):
    """The RHS integrator's steady state: u = B~^-1 (tau_c + D~ qdot - d), so the port
    delivers tau = tau_c while u cancels a constant d; tau_c carries an in-band
    excitation and a slow motion."""
    t = np.arange(0, 25, H)
    B_true, D_true = np.array([[1.1, 0.0], [0.05, 0.85]]), np.array([0.12, 0.15])
    qdot = np.stack([0.05 * np.sin(2 * np.pi * t / 11), 0.1 * np.sin(2 * np.pi * t / 30)], 1)
    qdot += np.stack([_multisine(t, [2e-3], [3.1]), _multisine(t, [2e-3], [4.3])], 1)
    tau_c = 0.02 * np.gradient(qdot, H, axis=0)
    d = np.tile(d_offset, (len(t), 1))
    u = np.linalg.solve(B_true, (tau_c + D_true * qdot - d).T).T
    tau = u @ B_true.T - D_true * qdot + d
    q = np.tile([0.3, 1.0], (len(t), 1))
    return t, q, 0.02 * qdot, qdot, u, tau, B_true


def test_constant_disturbance_does_not_collapse_B():
    """With d = [0.03, -0.02] N m (30 times the port torque) cancelled by u, the
    band-passed regularized learner keeps B_hat within 5 % of B~; the plain learner on
    the raw samples shrinks B_hat along d (it has no other way to fit u's offset)."""
    t, q, p, qdot, u, tau, B_true = _disturbed_closed_loop_data(np.array([0.03, -0.02]))
    relative = {}
    for mode in ("regularized", "plain"):
        identifier = _learn(_rows(t, q, p, qdot, u, tau, band=mode == "regularized"),
                            Learner(mode=mode))
        B, _ = identifier.Estimate(q[-1], p[-1])
        relative[mode] = np.linalg.norm(B - B_true) / np.linalg.norm(B_true)
    assert relative["regularized"] < 0.05, relative
    assert relative["plain"] > 0.2, relative


def test_change_detector_holds_after_a_jump_only():
    detector = ChangeDetector(ratio=5.0, floor=0.05, hold=2.0)
    state = ChangeDetector.InitialState()
    for k in range(10):                                   # a settled fit
        state = detector.Update(state, 0.1 * k, 1e-3 * (1 + 0.1 * (k % 3)))
    assert not ChangeDetector.Holding(state, 1.0)
    state = detector.Update(state, 1.0, 0.04)             # a jump below the floor
    assert not ChangeDetector.Holding(state, 1.0)
    state = detector.Update(state, 1.1, 0.5)              # an abrupt change
    assert ChangeDetector.Holding(state, 1.2) and ChangeDetector.Holding(state, 3.09)
    assert not ChangeDetector.Holding(state, 3.1)
    assert ChangeDetector.WindowStart(state) == pytest.approx(3.1)
    held = detector.Update(state, 2.0, 10.0)              # ignored while holding
    np.testing.assert_array_equal(held, state)
    for k in range(ChangeDetector.MIN_HISTORY - 1):       # a fresh history first
        state = detector.Update(state, 3.1 + 0.1 * k, 0.3)
    assert not ChangeDetector.Holding(state, 3.6)


def test_inertia_coupling_scales_the_couplings_into_lighter_joints():
    """learner.coupling "inertia": B_hat = F o mat(W_B h_B + b_B) with
    F_ij = min(1, m_i / m_j). The first estimate is still B0; the torch network and
    the numpy copy the fast loops evaluate agree at random weights; one Adam step
    moves the coupling from the heavy joint into the light one m_light / m_heavy
    times as far as the coupling the other way (Adam moves every raw output by
    about the learning rate); "uniform" is the unscaled network."""
    import torch
    from dacph_drake.learning.network import ExportedNetwork, RhsNetwork, coupling_factors
    inertias = [2.0, 0.01]
    F = coupling_factors("inertia", inertias)
    np.testing.assert_allclose(F, [[1.0, 1.0], [0.005, 1.0]])
    np.testing.assert_array_equal(coupling_factors("uniform", inertias), np.ones((2, 2)))
    with pytest.raises(ValueError, match=r"coupling = 'full'; allowed: uniform, inertia"):
        coupling_factors("full", inertias)
    B0_full = np.array([[1.1, 0.2], [0.003, 0.9]])
    network = RhsNetwork(2, [16, 8], B0_full, D0, 0.5, seed=0, coupling=F)
    q = torch.tensor([[0.3, -0.2]], dtype=torch.float64)
    p = torch.tensor([[0.1, 0.01]], dtype=torch.float64)
    np.testing.assert_allclose(network(q, p)[0][0].detach().numpy(), B0_full, atol=1e-15)
    exported = ExportedNetwork(2, [16, 8], 0.5, coupling=F)
    with torch.no_grad():
        for parameter in network.parameters():
            parameter.normal_()
    B, D = network(q, p)
    B_np, D_np = exported.Evaluate(network.export(), q[0].numpy(), p[0].numpy())
    np.testing.assert_allclose(B_np, B[0].detach().numpy(), rtol=1e-12)
    np.testing.assert_allclose(D_np, D[0].detach().numpy(), rtol=1e-12)
    settings = Learner(hidden=[16, 8], learning_rate=1e-3, steps_per_update=1)
    identifier = RhsIdentifier(2, settings, B0, D0, seed=0, coupling=F)
    t = np.arange(0.0, 2.0, H)
    u = np.stack([np.sin(2 * np.pi * 3.1 * t), np.sin(2 * np.pi * 4.3 * t)], axis=1)
    B_true = np.array([[1.0, 0.5], [0.5, 1.0]])                 # both couplings off
    zeros = np.zeros_like(u)
    rows = _rows(t, zeros, zeros, zeros, u, u @ B_true.T, band=False)
    before = identifier.Estimate(np.zeros(2), np.zeros(2))[0]
    identifier.Fit(rows, t[-1])
    step = np.abs(identifier.Estimate(np.zeros(2), np.zeros(2))[0] - before)
    assert step[1, 0] == pytest.approx(0.005 * step[0, 1], rel=0.2)
    assert step[0, 1] > 1e-4


def test_per_input_prior_lets_a_light_joint_learn_its_own_gain():
    """Two joints whose in-band inputs are three decades apart, both gains 20 % off
    B0. With the pooled prior (E_u, the mean square of all inputs, on every entry)
    the light joint's gain stays at B0, held by the heavy joint's input; with
    learner.prior_scale "per_input" (entry ij weighted by max(E_i, E_j)) it is
    learned like the heavy joint's, and the couplings stay at zero."""
    t = np.arange(0.0, 20.0, H)
    u = np.stack([_multisine(t, [1.0, 0.6], [3.1, 4.7]),
                  1e-3 * _multisine(t, [1.0, 0.6], [3.7, 5.3], phase=1.0)], axis=1)
    B_true = np.diag([1.2, 0.8])
    zeros = np.zeros_like(u)
    rows = _rows(t, zeros, zeros, zeros, u, u @ B_true.T, band=False)
    learned = {}
    for prior_scale in ("pooled", "per_input"):
        settings = Learner(prior_weight=0.1, prior_scale=prior_scale)
        learned[prior_scale] = _learn(rows, settings).Estimate(np.zeros(2), np.zeros(2))[0]
    assert learned["pooled"][0, 0] == pytest.approx(1.2, abs=0.03)
    assert learned["pooled"][1, 1] == pytest.approx(1.0, abs=0.03)
    assert learned["per_input"][0, 0] == pytest.approx(1.2, abs=0.03)
    assert learned["per_input"][1, 1] == pytest.approx(0.8, abs=0.03)
    assert np.abs(learned["per_input"][[0, 1], [1, 0]]).max() < 0.03


def test_the_step_guard_undoes_steps_that_raise_the_windows_loss():
    """Learner.step_guard: with a learning rate far too large, five Adam steps from
    the prior (B0, 10 % off the truth) leave the window's loss far above its value
    before them; the guard puts the network back (Fit returns False), without it
    the estimate moves. With the default rate the steps lower the loss and are
    kept."""
    t = np.arange(0.0, 2.0, H)
    u = np.stack([np.sin(2 * np.pi * 3.1 * t), np.sin(2 * np.pi * 4.3 * t)], axis=1)
    zeros = np.zeros_like(u)
    rows = _rows(t, zeros, zeros, zeros, u, u @ (0.9 * B0).T, band=False)
    for guard, kept in ((10.0, False), (0.0, True)):
        identifier = RhsIdentifier(2, Learner(learning_rate=1.0, step_guard=guard),
                                   B0, D0, seed=0)
        before = identifier.Export().copy()
        assert identifier.Fit(rows, t[-1]) is kept
        assert np.array_equal(identifier.Export(), before) is not kept
    identifier = RhsIdentifier(2, Learner(), B0, D0, seed=0)
    before = identifier.Statistics(rows, t[-1]).loss
    assert identifier.Fit(rows, t[-1]) is True
    assert identifier.Statistics(rows, t[-1]).loss < before


def test_one_identifier_fits_a_batch_as_independent_learners():
    """RhsIdentifier.ForTrials: Adam on the trials' stacked parameters is each
    trial's own torch.optim.Adam (its update, to round-off), a trial left out of a
    fit (holding) does not move, and a warm start restarts one trial's moments
    only: three trials with different priors, seeds and windows, fitted together
    and replayed alone."""
    import torch
    from dacph_drake.learning.network import RhsNetwork
    t = np.arange(0.0, 2.0, H)
    u = np.stack([np.sin(2 * np.pi * 3.1 * t), np.sin(2 * np.pi * 4.3 * t)], axis=1)
    qdot = np.stack([np.cos(2 * np.pi * 2.3 * t), np.sin(2 * np.pi * 5.1 * t)], axis=1)
    q, p = 0.3 * qdot, 0.01 * qdot
    truths = [np.array([[1.1, 0.1], [0.0, 0.8]]), np.array([[0.9, 0.0], [0.2, 1.3]]),
              np.array([[1.2, -0.1], [0.1, 1.0]])]
    rows = np.array([_rows(t, q, p, qdot, u, u @ B.T - D0 * qdot, band=False)
                     for B in truths])
    priors, seeds, starts = [B0, 1.1 * B0, 0.9 * B0], [0, 5, 9], [-np.inf, 0.5, 1.0]
    settings = Learner()
    batch = RhsIdentifier.ForTrials(2, settings, priors, [D0] * 3, seeds, [None] * 3)
    alone = [RhsIdentifier(2, settings, prior, D0, seed)
             for prior, seed in zip(priors, seeds)]
    untouched = batch.Export()[1].copy()
    batch.WarmStart(rows[2], t[-1], starts[2], trial=2)
    alone[2].WarmStart(rows[2], t[-1], starts[2])
    for _ in range(3):
        kept = batch.FitTrials(rows, t[-1], starts, np.array([True, False, True]))
        assert list(kept) == [True, False, True]
        for trial in (0, 2):
            alone[trial].Fit(rows[trial], t[-1], starts[trial])
    for trial in (0, 2):
        np.testing.assert_allclose(batch.Export()[trial], alone[trial].Export()[0],
                                   rtol=0, atol=1e-12)
    np.testing.assert_array_equal(batch.Export()[1], untouched)
    stats = batch.StatisticsOfTrials(rows, t[-1], starts)
    assert stats.loss[0] == pytest.approx(alone[0].Statistics(rows[0], t[-1]).loss,
                                          rel=1e-10)
    # One trial alone: torch.optim.Adam on an RhsNetwork of the same seed.
    network = RhsNetwork(2, settings.hidden, B0, D0, settings.momentum_scale, 0)
    adam = torch.optim.Adam(network.parameters(), lr=settings.learning_rate,
                            betas=(settings.beta1, settings.beta2), eps=settings.eps)
    single = RhsIdentifier(2, settings, B0, D0, 0)
    for _ in range(4):
        single.Fit(rows[0], t[-1])
        for _ in range(settings.steps_per_update):
            adam.zero_grad()
            times, q_, p_, qdot_, u_, tau_ = single._Split(rows[:1])
            w = single.Weights(times, t[-1], [-np.inf])
            B, D = network(q_[0], p_[0])
            B, D = B[None], D[None]
            loss = _window_loss(single, w, B, D, q_, qdot_, u_, tau_)
            loss.backward()
            adam.step()
    np.testing.assert_allclose(single.Export()[0], network.export(), rtol=0, atol=1e-12)


def _window_loss(identifier, w, B, D, q, qdot, u, tau):
    """The regularized loss of RhsIdentifier's docstring, written out for one
    trial's torch network (B, D evaluated by it)."""
    import torch
    from dacph_drake.learning.network import port_torque
    settings, n = Learner(), 2
    residual = tau - port_torque(B, D, u, qdot)
    data = torch.sum(w * torch.sum(residual**2, -1))
    E_u = torch.sum(w * torch.sum(u**2, -1)) / n
    E_q = torch.sum(w * torch.sum(qdot**2, -1)) / n
    prior = (E_u * torch.sum(w * torch.sum((B - torch.as_tensor(B0))**2, (2, 3)))
             + E_q * torch.sum(w * torch.sum((D - torch.as_tensor(D0))**2, -1)))
    return (data + settings.prior_weight * prior) / (E_u + E_q)

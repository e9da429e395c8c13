"""Column layout of the controllers' logs, shared by the systems that write them
(LhsController, RhsIntegrator, RhsLearner, AttitudeController) and the metrics, figures
and checks that read them."""


class LhsLog:
    """The columns of the LHS controller's log,
    lhs_log = [s (n), alpha~, alpha_d, V = s^T M s / 2, U(q), lambda_min(M)].

    Args:
        n: The number of joints.
    """

    def __init__(self, n: int):
        self.s = slice(0, n)
        self.alpha_error, self.alpha_desired, self.lyapunov_V = n, n + 1, n + 2
        self.size = n + 5


class RhsLog:
    """The columns of the RHS integrator's log,
    rhs_log = [e_tau (n), ||e_tau||, chi, K (n), c, c_min, dic_ok, trusted,
    certified, set_slowest, set_fastest]: trusted is 1 when this refresh adopted
    the learner's estimate; certified 1 while the estimate in use was adopted on its
    credible set's certificate (rhs.adoption certified_set), with that set's slowest
    and fastest mode ratios (kernels.certificate.certified_gains; nan without a set).

    Args:
        n: The number of joints.
    """

    def __init__(self, n: int):
        self.e_tau, self.e_norm, self.chi = slice(0, n), n, n + 1
        self.K = slice(n + 2, 2 * n + 2)
        (self.c, self.c_min, self.dic_ok, self.trusted, self.certified,
         self.set_slowest, self.set_fastest) = range(2 * n + 2, 2 * n + 9)
        self.size = 2 * n + 9


class RhsState:
    """The RHS integrator's two discrete-state groups (RhsIntegrator), read by index in
    kernels.loop.integrator_sample:

    fast, every RHS period:  [u_I (n), e_tau (n), ||e_tau||, chi, tau_c^r(k-1) (n)]
    model, every model period: [vec(B_hat^-1) (n*n), D_hat (n), K (n), c, c_min,
                                dic_ok, trusted, certified, set_slowest,
                                set_fastest, mode_low (n), mode_high (n)]
    rhs_log = [fast e_tau .. chi, model K .. trusted] (RhsLog).

    Args:
        n: The number of joints.
    """

    def __init__(self, n: int):
        self.u_I, self.e_tau = slice(0, n), slice(n, 2 * n)
        self.e_norm, self.chi = 2 * n, 2 * n + 1
        self.previous_request = slice(2 * n + 2, 3 * n + 2)
        self.fast_size = 3 * n + 2
        self.fast_logged = slice(n, 2 * n + 2)
        self.B_inverse, self.D_hat = slice(0, n * n), slice(n * n, n * n + n)
        self.K = slice(n * n + n, n * n + 2 * n)
        (self.c, self.c_min, self.dic_ok, self.trusted, self.certified,
         self.set_slowest, self.set_fastest) = range(n * n + 2 * n, n * n + 2 * n + 7)
        # The in-use credible set's range of each mode's eigenvalue (Gershgorin).
        self.mode_low = slice(n * n + 2 * n + 7, n * n + 3 * n + 7)
        self.mode_high = slice(n * n + 3 * n + 7, n * n + 4 * n + 7)
        self.model_size = n * n + 4 * n + 7
        self.model_logged = slice(n * n + n, n * n + 2 * n + 7)


class LearnerLog:
    """learner_log = [loss, beta_hat, nominal loss, holding, network published,
    undetermined, restarts, physical]: the fitted model's weighted squared residual on
    the window; the gain rule's 1 + RMS residual / RMS tau_obs; the nominal RHS's (B0,
    D0) residual on the same samples; 1 while nothing is learned (training paused after
    a change, learning.identification.ChangeDetector; no row of the local model
    determined); 1 while some published quantity is learned, 0 while all are the prior's
    (Learner.prior_fallback, a local model's undetermined rows; 0 in the learner-off
    ablation); the share of the n^2 + n quantities [B, diag D] published at the prior;
    the rows restarted this update (learning.local_bayes); physical: 1 while the
    observed port is in physical units, 0 once the inertial identifier reported the
    kinematics mismatched (scenario.inertia.fit_tolerance): the learned B and D are then
    the port's as the model sees it, and the metrics count them as the prior."""

    def __init__(self):
        (self.loss, self.beta_hat, self.nominal_loss, self.holding,
         self.network_published, self.undetermined, self.restarts,
         self.physical) = range(8)
        self.size = 8


class AttitudeLog:
    """attitude_log = [e (3), |e|, ||s||, V = s^T M s / 2, smallest link-base distance,
    R_d as a quaternion (w, x, y, z)] (AttitudeController, spatial robots)."""

    def __init__(self):
        self.e = slice(0, 3)
        self.e_norm, self.s_norm, self.lyapunov_V, self.clearance = 3, 4, 5, 6
        self.desired = slice(7, 11)
        self.size = 11


class PoseLog(AttitudeLog):
    """pose_log = attitude_log's columns, then e_p = p_E - p_d (3), |e_p|, p_d (3), in
    m (the pose task's AttitudeController)."""

    def __init__(self):
        super().__init__()
        self.e_position, self.e_position_norm = slice(11, 14), 14
        self.desired_position = slice(15, 18)
        self.size = 18

"""The controllers' logs by named columns (as Drake's namedview, with widths)."""
from typing import Tuple, Union


class LogColumns:
    """A log's columns in order: a scalar's index, a vector's slice; ``size``: the row's.

    Args:
        *columns: Each column: a name (a scalar) or (name, width) (a vector)."""

    def __init__(self, *columns: Union[str, Tuple[str, int]]):
        start = 0
        for column in columns:
            name, width = (column, None) if isinstance(column, str) else column
            setattr(self, name, start if width is None else slice(start, start + width))
            start += 1 if width is None else width
        self.size = start


class LhsLog(LogColumns):
    """lhs_log = [s (n), alpha~, alpha_d, V = s^T M s / 2, U(q), lambda_min(M)].

    Args:
        n: The number of joints."""

    def __init__(self, n: int):
        super().__init__(("s", n), "alpha_error", "alpha_desired",
                         "lyapunov_V", "potential", "lambda_min")


class RhsLog(LogColumns):
    """rhs_log = [e_tau (n), ||e_tau||, chi, K (n), c, c_min, dic_ok, trusted, certified,
    set_slowest, set_fastest]: trusted 1 when this refresh adopted the learner's estimate;
    certified 1 while the one in use was adopted on its credible set's certificate
    (rhs.adoption certified_set), with that set's slowest and fastest mode ratios
    (kernels.certificate.certified_gains; nan without a set).

    Args:
        n: The number of joints."""

    def __init__(self, n: int):
        super().__init__(("e_tau", n), "e_norm", "chi", ("K", n), "c",
                         "c_min", "dic_ok", "trusted", "certified",
                         "set_slowest", "set_fastest")


class RhsState:
    """The RHS integrator's two discrete-state groups (RhsIntegrator), read by index in
    kernels.loop.integrator_sample:

    fast, every RHS period:  [u_I (n), e_tau (n), ||e_tau||, chi, tau_c^r(k-1) (n)]
    model, every model period: [vec(B_hat^-1) (n*n), D_hat (n), K (n), c, c_min,
                                dic_ok, trusted, certified, set_slowest,
                                set_fastest, mode_low (n), mode_high (n)]
    rhs_log = [fast e_tau .. chi, model K .. trusted] (RhsLog).

    Args:
        n: The number of joints."""

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


class LearnerLog(LogColumns):
    """learner_log = [loss, beta_hat, nominal loss, holding, network published,
    undetermined, restarts, physical]: the fit's weighted squared residual on the window;
    the gain rule's 1 + RMS residual / RMS tau_obs; (B0, D0)'s residual on the same
    samples; 1 while nothing is learned (paused after a change; no local row determined);
    1 while some published quantity is learned (0: all the prior's, e.g. prior_fallback or
    learner off); the share of the n^2 + n quantities [B, diag D] at the prior; the rows
    restarted this update; 1 while the port is in physical units, 0 once the identifier
    reported the kinematics mismatched (inertia.fit_tolerance): the learned B and D are
    then the port's as the model sees it, and the metrics count them as the prior."""

    def __init__(self):
        super().__init__("loss", "beta_hat", "nominal_loss", "holding",
                         "network_published", "undetermined", "restarts",
                         "physical")


ATTITUDE_COLUMNS = (("e", 3), "e_norm", "s_norm", "lyapunov_V",
                    "clearance", ("desired", 4))


class AttitudeLog(LogColumns):
    """attitude_log = [e (3), |e|, ||s||, V = s^T M s / 2, clearance, R_d (w, x, y, z)]."""

    def __init__(self):
        super().__init__(*ATTITUDE_COLUMNS)


class PoseLog(LogColumns):
    """pose_log = attitude_log's, then e_p = p_E - p_d (3), |e_p|, p_d (3) [m]."""

    def __init__(self):
        super().__init__(*ATTITUDE_COLUMNS, ("e_position", 3), "e_position_norm",
                         ("desired_position", 3))

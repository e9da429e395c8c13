"""A region-of-attraction certificate for the LHS sliding dynamics, by sums of
squares (Drake's ``RegionOfAttraction`` with the open-source Clarabel solver).

Polynomial model (its assumptions are part of the certificate):
- frozen configuration q (M and the Christoffel symbols Gamma evaluated at q),
- nu = 0 (the joint rates are s), exact RHS (e_tau = 0),
- tanh(x) replaced by its cubic Taylor polynomial x - x^3 / 3,

    M(q) sdot = -C'(q, s) s - K_d s - chi (s / epsilon - (s / epsilon)^3 / 3),
    C'(q, s) = sum_k s_k Gamma_k(q).

With the candidate V = s^T M(q) s / 2, the certified region is {V(s) <= rho}; it
contains the ball ||s|| <= sqrt(2 rho / lambda_max(M(q)))."""
from dataclasses import asdict, dataclass

import numpy as np
from pydrake.solvers import ClarabelSolver
from pydrake.symbolic import Evaluate as EvaluateExpression
from pydrake.symbolic import MakeVectorVariable
from pydrake.systems.analysis import (RegionOfAttraction,
                                      RegionOfAttractionOptions)
from pydrake.systems.primitives import SymbolicVectorSystem

from dacph_drake.reduced_model import ReducedOrderModel


@dataclass
class RegionCertificate:
    q: list
    rho: float                      # level of V = s^T M s / 2 [J]
    radius: float                   # a ball ||s|| <= radius inside the region [rad/s]
    assumptions: str

    def as_dict(self):
        return asdict(self)


ASSUMPTIONS = ("frozen configuration q; nu = 0; e_tau = 0; tanh replaced by its "
               "cubic Taylor polynomial; candidate V = s^T M(q) s / 2")


def sliding_region_of_attraction(model: ReducedOrderModel, q: np.ndarray, Kd: float,
                                 chi: float, epsilon: float) -> RegionCertificate:
    n = model.num_joints
    M = model.Evaluate(q, np.zeros(n)).M
    Gamma = [model.Evaluate(q, np.eye(n)[k]).C for k in range(n)]
    s = MakeVectorVariable(n, "s")
    # numpy's object-array arithmetic on symbolic expressions reports stale
    # floating-point status flags as warnings; nothing numeric happens here.
    with np.errstate(invalid="ignore", divide="ignore"):
        x = s / epsilon
        C_s = sum(s[k] * Gamma[k] for k in range(n))
        force = C_s @ s + Kd * s + chi * (x - x**3 / 3)
        dynamics = -np.linalg.solve(M, np.eye(n)) @ force
        V = 0.5 * s.dot(M @ s)
    system = SymbolicVectorSystem(state=s, dynamics=dynamics)
    options = RegionOfAttractionOptions()
    options.lyapunov_candidate = V
    options.state_variables = s
    options.solver_id = ClarabelSolver.id()
    scaled = RegionOfAttraction(system, system.CreateDefaultContext(), options)
    probe = {s[0]: 1.0, **{s[k]: 0.0 for k in range(1, n)}}
    rho = float(EvaluateExpression([V], probe)[0, 0]
                / EvaluateExpression([scaled], probe)[0, 0])
    radius = float(np.sqrt(2 * rho / np.max(np.linalg.eigvalsh(M))))
    return RegionCertificate(q=[float(v) for v in q], rho=rho, radius=radius,
                             assumptions=ASSUMPTIONS)

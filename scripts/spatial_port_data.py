"""What the learner's data say on a spatial robot (docs/results/spatial.md): runs
the learner-off DAC loop (dac-nominal) of a shipped spatial scenario and, at the end
of each phase, fits B and D by least squares, joint by joint, to the last 2 s of the
learner's own band-passed port samples, next to the ground truth's B~, D~ at that
instant. "resid truth" is the part of the in-band port torque that the true
tau = B~ u - D~ qdot does not explain: where it is comparable to the torque itself,
the samples do not carry B~ and D~, and no learner can beat the prior on them.

    .venv/bin/python scripts/spatial_port_data.py satellite_3dof
"""
import argparse

import numpy as np

from dacph_drake.controllers import build_closed_loop
from dacph_drake.learning.identification import PortSample
from dacph_drake.assembly.scenario_files import load_scenario

WINDOW = 200            # the newest samples fitted (2 s at the 10 ms sample period)


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("scenario", nargs="?", default="satellite_3dof")
    args = parser.parse_args()
    scenario = load_scenario(args.scenario)
    loop = build_closed_loop("dac-nominal", scenario)
    n, layout = loop.model.num_joints, PortSample(loop.model.num_joints)
    learner, truth = loop.systems["learner"], loop.systems["true_rhs"]
    simulator = loop.CreateSimulator()
    context = simulator.get_mutable_context()
    phases = scenario.phases
    np.set_printoptions(precision=4, suppress=True, linewidth=160)
    for t in (phases.nonlinear_start, phases.disturbance_start, scenario.duration):
        simulator.AdvanceTo(t - 0.1)
        rows = learner.GetMyContextFromRoot(context).get_discrete_state(
            learner._buffer).get_value().reshape(-1, 1 + layout.size)
        rows = rows[np.argsort(rows[:, 0])][-WINDOW:, 1:]
        u, qdot, tau = rows[:, layout.u], rows[:, layout.qdot], rows[:, layout.tau]
        matrices = truth.GetOutputPort("true_matrices").Eval(
            truth.GetMyContextFromRoot(context))
        B, D = matrices[:n * n].reshape(n, n), matrices[n * n:]
        print(f"t = {t - 0.1:.1f} s")
        for i in range(n):
            regressors = np.hstack([u, -qdot[:, i:i + 1]])
            fit = np.linalg.lstsq(regressors, tau[:, i], rcond=None)[0]
            rms = np.sqrt(np.mean(tau[:, i]**2))
            unexplained = np.sqrt(np.mean((tau[:, i] - u @ B[i] + D[i] * qdot[:, i])**2))
            print(f"  joint {i + 1}: B row fitted {fit[:n]} true {B[i]}; D fitted "
                  f"{fit[n]:.4f} true {D[i]:.4f}; in-band torque RMS {rms:.2e} N m, "
                  f"unexplained by the truth {unexplained / rms:.0%}")


if __name__ == "__main__":
    main()

"""Speed figures for the README (run: .venv/bin/python scripts/bench.py).

Each comparison is a ratio measured in this one run (the machines are shared).
"""
import argparse
import time

import numpy as np

from dacph_drake.free_flight import run_free_flight
from dacph_drake.plant import MakeArmPlant
from dacph_drake.reduced_model import ReducedOrderModel
from dacph_drake.robot import RobotParams


def _best_of(fn, repeats=5, number=2000) -> float:
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - start) / number)
    return best


def bench_reduced_model():
    model = ReducedOrderModel(MakeArmPlant(RobotParams()))
    q, qdot = np.array([0.3, 1.2]), np.array([0.5, -0.2])
    q_full = np.concatenate([[0.0, 0.0, 0.1], q])
    evaluate = _best_of(lambda: model.Evaluate(q, qdot))
    ee_gjm = _best_of(lambda: model.EndEffectorJacobian(q_full))
    print(f"reduced model Evaluate (M, Mdot, dM/dq, C', dH/dq, D, dD/dq): "
          f"{evaluate * 1e6:.1f} us  (target <= 20 us)")
    print(f"end-effector GJM (6 x n, full pose):                          "
          f"{ee_gjm * 1e6:.1f} us")


def bench_plant_integration(duration: float):
    print(f"free flight of the ground truth, {duration:g} s, smooth torques:")
    args = dict(amplitudes=[0.006, 0.006], frequencies=[3.0, 4.0], q0=[0.3, 0.3])
    for scheme, step in [("runge_kutta2", 2.5e-4), ("runge_kutta3", 2.5e-4),
                         ("runge_kutta3", 1e-3), ("runge_kutta5", 1e-3)]:
        start = time.perf_counter()
        r = run_free_flight(RobotParams(), duration, integration_scheme=scheme,
                            step=step, **args)
        wall = time.perf_counter() - start
        print(f"  {scheme:13s} h = {step * 1e3:.2f} ms: max|momentum| "
              f"{r.max_momentum:.1e}, |KE - W|/KE "
              f"{abs(r.kinetic_energy - r.work) / r.kinetic_energy:.1e}, "
              f"wall {wall:.2f} s")
    r = run_free_flight(RobotParams(), duration, time_step=2.5e-4, **args)
    print(f"  discrete plant h = 0.25 ms: max|momentum| {r.max_momentum:.1e}")


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--duration", type=float, default=20.0)
    args = parser.parse_args()
    bench_reduced_model()
    bench_plant_integration(args.duration)


if __name__ == "__main__":
    main()

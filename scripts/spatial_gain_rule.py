"""The RHS gain rule at scale: inf_q lambda_min(M) by multi-start search
(dacph_drake.dynamics.inertia_bound) for the planar arms and the shipped spatial robots, and
the decay rate c_min (eq. 48) and RHS period it asks for at the default scenario's
gains (Td, Kd, rhs.beta_max, rhs.c_margin), and with the LHS damping scaled to the
inertia instead (K_d = damping_rate M, the spatial loop's AttitudeGains).

    .venv/bin/python scripts/spatial_gain_rule.py
"""
import time

from dacph_drake.robots.description import SPATIAL_ROBOTS, MakeRobotPlant
from dacph_drake.dynamics.floating_model import FloatingBaseModel
from dacph_drake.gain_rule import (WELL_DAMPED_LOOP_GAIN, c_lower_bound,
                                   inertia_scaled_c_lower_bound)
from dacph_drake.dynamics.inertia_bound import search_inertia_bound
from dacph_drake.dynamics.plant import MakeArmPlant
from dacph_drake.dynamics.reduced_model import ReducedOrderModel, mass_matrix_bounds
from dacph_drake.scenario.planar_arm import RobotParams, unequal_three_link_arm
from dacph_drake.scenario import AttitudeGains, Scenario


def main() -> None:
    scenario = Scenario()
    Td, Kd, rhs = scenario.rhs.Td, scenario.task.gains.Kd, scenario.rhs
    robots = [("planar 2-link (paper)", MakeArmPlant(RobotParams()), True),
              ("planar 3-link (tests)", MakeArmPlant(unequal_three_link_arm()), True)]
    robots += [(name, MakeRobotPlant(name), False) for name in SPATIAL_ROBOTS]
    print(f"gain rule at Td = {Td:g}, Kd = {Kd:g}, beta_max = {rhs.beta_max:g}, "
          f"c_margin = {rhs.c_margin:g}; search: 24 starts, 5 % safety margin")
    damping_rate = AttitudeGains().damping_rate
    print("| robot | n | grid inf lambda_min (73^n) | searched | starts within 0.1 % | "
          "search time | c_min (beta = 1) | RHS period needed | with K_d = "
          f"{damping_rate:g} M: c_min, RHS period |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, plant, planar in robots:
        model = FloatingBaseModel(plant)
        grid = "-"
        if planar:
            start = time.perf_counter()
            lo, _ = mass_matrix_bounds(ReducedOrderModel(plant))
            grid = f"{lo:.5g} kg m^2 ({time.perf_counter() - start:.1f} s)"
        bound = search_inertia_bound(model)
        c_nominal = c_lower_bound(Td, Kd, bound.lambda_min, 1.0)
        c_largest = (1 + rhs.c_margin) * c_lower_bound(Td, Kd, bound.lambda_min,
                                                       rhs.beta_max)
        period = WELL_DAMPED_LOOP_GAIN / c_largest
        scaled = inertia_scaled_c_lower_bound(Td, damping_rate, 1.0)
        scaled_period = WELL_DAMPED_LOOP_GAIN / ((1 + rhs.c_margin) * (
            inertia_scaled_c_lower_bound(Td, damping_rate, rhs.beta_max)))
        print(f"| {name} | {model.num_joints} | {grid} | {bound.smallest_found:.5g} kg m^2 "
              f"| {bound.starts_at_minimum}/{bound.starts} | {bound.seconds:.1f} s | "
              f"{c_nominal:.0f} 1/s | {period * 1e6:.1f} us ({1e-3 / period:.1f} kHz) | "
              f"{scaled:.0f} 1/s, {scaled_period * 1e3:.2f} ms |")


if __name__ == "__main__":
    main()

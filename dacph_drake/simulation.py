"""Simulator set-up shared by every diagram in the package."""
from pydrake.systems.analysis import (ApplySimulatorConfig, Simulator,
                                      SimulatorConfig)

INTEGRATION_SCHEMES = ("runge_kutta2", "runge_kutta3", "runge_kutta5")


def MakeSimulator(diagram, integration_scheme: str = "runge_kutta3",
                  step: float = 2.5e-4) -> Simulator:
    """A Simulator for ``diagram`` with a fixed-step explicit Runge-Kutta integrator.

    Fixed steps because the closed loop's discrete updates stop the integrator at
    every RHS sample anyway; at 0.25 ms, RK3 conserves the free-floating arm's
    momentum to ~1e-13 (tests/test_plant.py).
    """
    simulator = Simulator(diagram)
    ApplySimulatorConfig(SimulatorConfig(
        integration_scheme=integration_scheme, max_step_size=step,
        use_error_control=False, target_realtime_rate=0.0), simulator)
    return simulator

"""The simulator of every diagram in the package: Drake's Simulator with a scenario's
``simulator:`` settings (scenario.simulator) applied."""
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator, SimulatorConfig
from pydrake.systems.framework import Diagram


def MakeSimulator(diagram: Diagram, config: SimulatorConfig) -> Simulator:
    """Makes a Simulator for a diagram with a configuration applied.

    Args:
        diagram: The diagram.
        config: The simulator configuration
            (scenario.simulator.validate_simulator_config)."""
    simulator = Simulator(diagram)
    ApplySimulatorConfig(config, simulator)
    return simulator

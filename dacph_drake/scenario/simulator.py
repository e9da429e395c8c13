"""The ``simulator:`` section, Drake's SimulatorConfig: its default, check and Simulator."""
import copyreg

from pydrake.systems.analysis import ApplySimulatorConfig, Simulator, SimulatorConfig
from pydrake.systems.framework import Diagram

from dacph_drake.scenario.errors import (ConfigError, require_in_range, require_nonnegative,
                                require_one_of)

# Explicit Runge-Kutta schemes: the closed loop's Python systems have no AutoDiff
# form for an implicit scheme's Jacobian; each of these keeps the free-floating arm's
# momentum to ~1e-13 at 0.25 ms (tests/test_plant.py).
INTEGRATION_SCHEMES = ("runge_kutta2", "runge_kutta3", "runge_kutta5")
# Schemes with an embedded error estimate (use_error_control: true).
ERROR_CONTROLLED_SCHEMES = ("runge_kutta3", "runge_kutta5")


def FixedStepConfig(integration_scheme: str = "runge_kutta2",
                    step: float = 2.5e-4) -> SimulatorConfig:
    """Drake's SimulatorConfig for a fixed-step explicit Runge-Kutta integrator, unpaced:
    the loop's discrete updates stop it at every RHS sample anyway (min(step, periods.rhs)).

    Args:
        integration_scheme: Drake's scheme name (runge_kutta2, 3 or 5).
        step: The largest step [s]."""
    return SimulatorConfig(integration_scheme=integration_scheme, max_step_size=step,
                           use_error_control=False, target_realtime_rate=0.0)


def validate_simulator_config(config: SimulatorConfig) -> None:
    """Requires a simulator configuration a closed loop can run.

    Args:
        config: A scenario's ``simulator:`` (Drake's SimulatorConfig).

    Raises:
        ConfigError: Naming the first simulator.* setting a closed loop cannot run."""
    require_one_of("simulator.integration_scheme", config.integration_scheme,
                   INTEGRATION_SCHEMES)
    require_in_range("simulator.max_step_size", config.max_step_size, 1e-7, 1.0, "s")
    if config.use_error_control:
        if config.integration_scheme not in ERROR_CONTROLLED_SCHEMES:
            raise ConfigError(
                f"simulator.use_error_control = true with simulator.integration_scheme "
                f"= {config.integration_scheme!r}, which has no error estimate; allowed: "
                f"false, or a scheme among {', '.join(ERROR_CONTROLLED_SCHEMES)}")
        require_in_range("simulator.accuracy", config.accuracy, 1e-12, 1.0)
    if config.start_time != 0.0:
        raise ConfigError(f"simulator.start_time = {config.start_time:g} s; allowed: 0 "
                          "(the phases are times from the start of the run)")
    require_nonnegative("simulator.target_realtime_rate", config.target_realtime_rate)
    if config.publish_every_time_step:
        raise ConfigError("simulator.publish_every_time_step = true; allowed: false (the "
                          "logs are sampled at the log period; a publish at every step "
                          "would add samples between them)")


def _simulator_config(settings: dict) -> SimulatorConfig:
    return SimulatorConfig(**settings)


def _reduce_simulator_config(config: SimulatorConfig):
    return _simulator_config, ({f.name: getattr(config, f.name)
                                for f in SimulatorConfig.__fields__},)


# A scenario travels to sweep workers by pickle; pydrake's SimulatorConfig has no
# pickle support of its own, so it travels as its fields.
copyreg.pickle(SimulatorConfig, _reduce_simulator_config)


def MakeSimulator(diagram: Diagram, config: SimulatorConfig) -> Simulator:
    """Makes a Simulator for a diagram with a configuration applied.

    Args:
        diagram: The diagram.
        config: The simulator configuration (validate_simulator_config)."""
    simulator = Simulator(diagram)
    ApplySimulatorConfig(config, simulator)
    return simulator

"""Error types shared by the package."""


class ConfigError(ValueError):
    """A setting is invalid. The message names the setting and its allowed range."""


class SimulationDiverged(RuntimeError):
    """A simulation stopped because its state became non-finite or ran away."""


def require_positive(name: str, value: float, unit: str = "") -> None:
    """Raises ConfigError unless ``value`` is a finite number > 0."""
    _require(name, value, value > 0, f"> 0{(' ' + unit) if unit else ''}")


def require_nonnegative(name: str, value: float, unit: str = "") -> None:
    """Raises ConfigError unless ``value`` is a finite number >= 0."""
    _require(name, value, value >= 0, f">= 0{(' ' + unit) if unit else ''}")


def require_in_range(name: str, value: float, low: float, high: float,
                     unit: str = "") -> None:
    """Raises ConfigError unless low <= value <= high."""
    _require(name, value, low <= value <= high,
             f"in [{low:g}, {high:g}]{(' ' + unit) if unit else ''}")


def _require(name: str, value: float, ok: bool, allowed: str) -> None:
    try:
        finite = float(value) == float(value) and abs(float(value)) != float("inf")
    except (TypeError, ValueError):
        raise ConfigError(f"{name} = {value!r} is not a number; allowed: {allowed}")
    if not (finite and ok):
        raise ConfigError(f"{name} = {value!r} is out of range; allowed: {allowed}")

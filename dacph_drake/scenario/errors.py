"""Error types shared by the package, and the checks that raise them."""
import dataclasses
import math
import numbers
import typing
from typing import Iterable

import numpy as np


class ConfigError(ValueError):
    """A setting is invalid. The message names the setting and its allowed range."""


def require_positive(name: str, value: float, unit: str = "") -> None:
    """Requires a finite number > 0.

    Args:
        name: The setting's name, for the message.
        value: Its value.
        unit: Its unit, for the message.

    Raises:
        ConfigError: Naming the setting and what is allowed."""
    _require(name, value, value > 0, f"> 0{(' ' + unit) if unit else ''}")


def require_nonnegative(name: str, value: float, unit: str = "") -> None:
    """Requires a finite number >= 0.

    Args:
        name: The setting's name, for the message.
        value: Its value.
        unit: Its unit, for the message.

    Raises:
        ConfigError: Naming the setting and what is allowed."""
    _require(name, value, value >= 0, f">= 0{(' ' + unit) if unit else ''}")


def require_in_range(name: str, value: float, low: float, high: float,
                     unit: str = "") -> None:
    """Requires a finite number in [low, high].

    Args:
        name: The setting's name, for the message.
        value: Its value.
        low: The smallest allowed value.
        high: The largest allowed value.
        unit: Its unit, for the message.

    Raises:
        ConfigError: Naming the setting and what is allowed."""
    _require(name, value, low <= value <= high,
             f"in [{low:g}, {high:g}]{(' ' + unit) if unit else ''}")


def require_one_of(name: str, value: object, allowed: Iterable[str]) -> None:
    """Requires one of a set of names.

    Args:
        name: The setting's name, for the message.
        value: Its value.
        allowed: The allowed names, listed in the message.

    Raises:
        ConfigError: Naming the setting and the allowed names."""
    if value not in allowed:
        raise ConfigError(f"{name} = {value!r}; allowed: {', '.join(allowed)}")


def _require(name: str, value: float, ok: bool, allowed: str) -> None:
    value = _plain(value)
    try:
        finite = float(value) == float(value) and abs(float(value)) != float("inf")
    except (TypeError, ValueError):
        raise ConfigError(f"{name} = {value!r} is not a number; allowed: {allowed}")
    if not (finite and ok):
        raise ConfigError(f"{name} = {value!r} is out of range; allowed: {allowed}")


def require_setting_types(name: str, value: object) -> None:
    """Requires each setting of a dataclass, recursively, of its declared kind (in Python).

    Args:
        name: The setting's dotted path, for the message ("" for the root).
        value: A dataclass instance.

    Raises:
        ConfigError: Naming the first setting of another kind."""
    for f in dataclasses.fields(value):
        _require_kind(f"{name}.{f.name}" if name else f.name, getattr(value, f.name),
                      f.type)


def _require_kind(name: str, value: object, declared: object) -> None:
    """Requires ``value`` to be of the ``declared`` kind; unknown kinds pass."""
    origin, arguments = typing.get_origin(declared), typing.get_args(declared)
    if declared in (float, int):
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ConfigError(f"{name} = {_plain(value)!r} is not a number; allowed: a "
                              "finite number")
    elif origin is list:
        if not isinstance(value, (list, tuple, np.ndarray)):
            raise ConfigError(f"{name} = {_plain(value)!r} is not a list; allowed: a "
                              "list")
        for i, entry in enumerate(value):
            _require_kind(f"{name}[{i}]", entry, arguments[0])
    elif origin is dict:
        if not isinstance(value, dict):
            raise ConfigError(f"{name} = {value!r} is not a mapping; allowed: a mapping")
        for key, entry in value.items():
            _require_kind(f"{name}.{key}", entry, arguments[1])
    elif origin is typing.Union:
        if value is None and type(None) in arguments:
            return
        sections = [kind for kind in arguments if dataclasses.is_dataclass(kind)]
        if sections and not isinstance(value, tuple(sections)):
            raise ConfigError(f"{name} is a {type(value).__name__}; allowed: "
                              f"{' or '.join(kind.__name__ for kind in sections)}")
        if sections:
            require_setting_types(name, value)
    elif dataclasses.is_dataclass(declared):
        if not isinstance(value, declared):
            raise ConfigError(f"{name} = {value!r} is not a mapping; allowed: a "
                              f"{declared.__name__} section")
        require_setting_types(name, value)


def require_finite_numbers(name: str, value: object) -> None:
    """Requires every number of a setting, walked recursively, to be finite.

    Args:
        name: The setting's dotted path, for the message.
        value: A dataclass, a list or a number.

    Raises:
        ConfigError: Naming the first NaN, infinity, or string where a number belongs."""
    if dataclasses.is_dataclass(value):
        for f in dataclasses.fields(value):
            if not _holds_strings(f.type):
                require_finite_numbers(f"{name}.{f.name}" if name else f.name,
                                       getattr(value, f.name))
    elif isinstance(value, (list, tuple)):
        for i, entry in enumerate(value):
            require_finite_numbers(f"{name}[{i}]", entry)
    elif isinstance(value, str):
        raise ConfigError(f"{name} = {value!r} is not a number; allowed: a finite number")
    elif isinstance(value, (int, float)) and not math.isfinite(value):
        raise ConfigError(f"{name} = {_plain(value)!r} is not finite; allowed: a finite "
                          "number")


def _holds_strings(declared: object) -> bool:
    """Whether a field declared so holds strings (str, or a list or mapping of str)."""
    arguments = typing.get_args(declared)
    return declared is str or (typing.get_origin(declared) in (list, dict)
                               and arguments[-1] is str)


def _plain(value):
    """A numpy scalar as the Python number it holds (a plain repr), else unchanged."""
    return value.item() if type(value).__module__ == "numpy" and hasattr(value, "item") \
        else value

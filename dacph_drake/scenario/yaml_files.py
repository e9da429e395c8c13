"""YAML files as tagged plain values (read_yaml) or a typed dataclass, every key and kind
checked first (load_yaml_dataclass): one line naming file and setting, no traceback."""
import dataclasses
import difflib
import logging
import typing
from pathlib import Path
from typing import Any, Callable, List, Optional, Sequence, Type, TypeVar, Union

import yaml
from pydrake.common.yaml import yaml_load_typed

from dacph_drake.scenario.errors import ConfigError

_Schema = TypeVar("_Schema")


def read_yaml(path: Union[str, Path]) -> Any:
    """Reads a YAML file as plain values (tagged mappings as _TaggedMapping; {} if empty).

    Args:
        path: The file.

    Raises:
        ConfigError: Naming the file: malformed YAML (line and column) or unreadable."""
    try:
        with open(path, encoding="utf-8") as f:
            raw = yaml.load(f, Loader=_TaggedLoader)
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark
        raise ConfigError(f"{path}: malformed YAML at line {mark.line + 1}, column "
                          f"{mark.column + 1}: {e.problem}") from e
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as e:
        raise ConfigError(f"{path}: cannot be read ({e}); allowed: a readable UTF-8 "
                          "YAML file") from e
    return raw if raw is not None else {}


def load_yaml_dataclass(path: str, schema: Type[_Schema],
                        noted_defaults: Sequence[str] = (),
                        migrate: Optional[Callable[[Any, str], Any]] = None,
                        defaults: Optional[_Schema] = None) -> _Schema:
    """yaml_load_typed with one-line errors that name the file.

    Args:
        path: The YAML file.
        schema: The dataclass it holds.
        noted_defaults: Top-level sections the file may omit, with a logged warning.
        migrate: ``migrate(raw, path)``: the parsed file with older settings moved, or None.
        defaults: The schema object the file's settings replace (default: the schema's).

    Raises:
        ConfigError: Malformed YAML, a value of the wrong kind, or unknown keys."""
    raw = read_yaml(path)
    migrated = migrate(raw, path) if migrate is not None else None
    raw = migrated if migrated is not None else raw
    _check_kinds(raw, schema, f"{path}: ")
    missing = [name for name in noted_defaults
               if not (isinstance(raw, dict) and name in raw)]
    if missing:
        logging.getLogger(__name__).warning(
            "%s: no %s section; using the defaults (the paper's robot)", path,
            " or ".join(f"{name}:" for name in missing))
    try:
        if migrated is not None:
            return yaml_load_typed(schema=schema, data=yaml.dump(
                migrated, Dumper=_TaggedDumper), defaults=defaults)
        return yaml_load_typed(schema=schema, filename=str(path), defaults=defaults)
    except (RuntimeError, ValueError, TypeError) as e:
        raise ConfigError(f"{path}: {str(e).splitlines()[0]}") from e


class _TaggedLoader(yaml.SafeLoader):
    """PyYAML's safe loader reading a tagged node (e.g. !Uniform) as its untagged value."""


def _construct_unique_mapping(loader, node, deep=False):
    """A mapping with each key once (PyYAML silently keeps a repeated key's last value)."""
    seen = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=True)
        line = key_node.start_mark.line + 1
        if key in seen:
            raise ConfigError(f"{key_node.start_mark.name}: {key} is given twice (lines "
                              f"{seen[key]} and {line}); allowed: each setting once")
        seen[key] = line
    return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)


_TaggedLoader.construct_mapping = _construct_unique_mapping


class _TaggedMapping(dict):
    """A mapping read with its YAML tag (``tag``: the name after the !)."""
    tag = ""


def _construct_untagged(loader, suffix, node):
    if isinstance(node, yaml.MappingNode):
        mapping = _TaggedMapping(loader.construct_mapping(node, deep=True))
        mapping.tag = suffix
        return mapping
    if isinstance(node, yaml.SequenceNode):
        return loader.construct_sequence(node, deep=True)
    return loader.construct_scalar(node)


_TaggedLoader.add_multi_constructor("!", _construct_untagged)


class _TaggedDumper(yaml.SafeDumper):
    """PyYAML's safe dumper writing a _TaggedMapping with its tag."""


_TaggedDumper.add_representer(_TaggedMapping, lambda dumper, mapping: (
    dumper.represent_mapping(f"!{mapping.tag}" if mapping.tag else
                             "tag:yaml.org,2002:map", mapping)))


def _check_kinds(raw, schema, where: str, name: str = "") -> None:
    """Raises ConfigError at the first setting of ``raw`` not of ``schema``'s kind."""
    shown = name or "the file"
    if typing.get_origin(schema) is typing.Union and all(
            dataclasses.is_dataclass(member) for member in typing.get_args(schema)):
        members = {member.__name__: member for member in typing.get_args(schema)}
        tag = getattr(raw, "tag", "")
        if tag not in members and tag:
            raise ConfigError(f"{where}{shown} has the tag !{tag}; allowed: "
                              f"{', '.join('!' + m for m in members)} (none: "
                              f"{typing.get_args(schema)[0].__name__})")
        schema = members[tag] if tag else typing.get_args(schema)[0]
    if dataclasses.is_dataclass(schema):
        if not isinstance(raw, dict):
            raise ConfigError(f"{where}{shown} = {raw!r} is not a mapping; allowed: a "
                              f"section of settings")
        tag = getattr(raw, "tag", "")
        if tag and tag != schema.__name__:
            raise ConfigError(f"{where}{shown} has the tag !{tag}, which this section "
                              f"does not take; allowed: no tag (a {schema.__name__} "
                              "section of settings)")
        types = {f.name: f.type for f in dataclasses.fields(schema)}
        unknown = [key for key in raw if key not in types]
        if unknown:
            guesses = [(f"{close[0]!r}" if len(unknown) == 1 else
                        f"{close[0]!r} for {key!r}") for key in unknown
                       for close in [difflib.get_close_matches(str(key), list(types), 1)]
                       if close]
            raise ConfigError(
                f"{where}{name or 'top level'}: the fields {unknown} were unknown"
                + (f" (did you mean {', '.join(guesses)}?)" if guesses else "")
                + f"; allowed: {', '.join(types)}")
        for key, value in raw.items():
            _check_kinds(value, types[key], where, f"{name}.{key}" if name else key)
    elif typing.get_origin(schema) in (list, List):
        if not isinstance(raw, list):
            raise ConfigError(f"{where}{shown} = {raw!r} is not a list; allowed: a list "
                              "[...]")
        for i, value in enumerate(raw):
            _check_kinds(value, typing.get_args(schema)[0], where, f"{name}[{i}]")
    elif schema in (float, int) and not _reads_as_number(raw):
        raise ConfigError(f"{where}{shown} = {raw!r} is not a number; allowed: a "
                          f"{'whole ' if schema is int else ''}number")
    elif schema is int and not _reads_as_whole_number(raw):
        leaf = shown.rpartition(".")[2].partition("[")[0]
        raise ConfigError(f"{where}{shown} = {raw!r} is not a whole number (an int "
                          f"value for {leaf!r}); allowed: a whole number (e.g. 1, not "
                          "1.5 or 1.0)")


def _reads_as_whole_number(raw) -> bool:
    """Whether a YAML scalar is an integer to Drake's YAML reader (1, not 1.0)."""
    try:
        int(str(raw), 0)
    except ValueError:
        return False
    return True


def _reads_as_number(raw) -> bool:
    """Whether a YAML scalar is a number to Drake's YAML reader (which also reads 1e-3)."""
    if isinstance(raw, bool) or raw is None or isinstance(raw, (list, dict)):
        return False
    try:
        float(raw)
    except (TypeError, ValueError):
        return False
    return True

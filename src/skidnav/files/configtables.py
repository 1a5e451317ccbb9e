"""The conventions every TOML config loader follows (experiments, tuning, real-time runs, studies).

A problem is one :class:`~skidnav.errors.UserError` line, a bad key or value named first
(:class:`~skidnav.errors.ConfigError`: ``"PROBLEM in WHERE"``), where ``WHERE`` names the file and
the table (``[run]``, ``[[maps]] #2``, ``[tune.space.q-learning]``) and a value read from the
file is quoted in part (:func:`~skidnav.errors.shown`). A path in a config is relative to
the config file's folder. A config the code writes (``tuned.toml``, a study shortcut's config)
spells its values with :func:`toml_value` and :func:`toml_key`.
"""

from __future__ import annotations

import dataclasses
import difflib
import json
import math
import re
import types
import typing
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, TypeVar

from skidnav.errors import ConfigError, ConfigKeyError, UserError, shown, within

T = TypeVar("T")

__all__ = [
    "build_dataclass",
    "check_keys",
    "check_types",
    "resolve_path",
    "table",
    "table_array",
    "toml_document",
    "toml_key",
    "toml_value",
]

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")
_KINDS: dict[type, str] = {
    bool: "true or false", int: "an integer", float: "a number", str: "a string",
}  # fmt: skip
"""The field types a TOML value is checked against by :func:`check_types`, as a message words
them."""


def table(value: Any, where: str) -> dict[str, Any]:
    """``value`` if it is a TOML table; UserError ``"{where}: expected a table, got …"`` otherwise.

    >>> table({"a": 1}, "[run]")
    {'a': 1}
    >>> table(3, "[run]")
    Traceback (most recent call last):
    ...
    skidnav.errors.UserError: [run]: expected a table, got 3
    """
    if not isinstance(value, dict):
        raise UserError(f"{where}: expected a table, got {shown(value)}")
    return value


def table_array(value: Any, name: str) -> list[dict[str, Any]]:
    """The tables of a non-empty TOML array of tables ``[[name]]``; UserError otherwise (an item
    that is not a table is named ``[[name]] #N``, counting from 1)."""
    if not isinstance(value, list) or not value:
        raise UserError(f"expected at least one [[{name}]] table")
    return [table(item, f"[[{name}]] #{n + 1}") for n, item in enumerate(value)]


def check_keys(values: Iterable[str], known: Iterable[str], where: str = "") -> None:
    """:class:`~skidnav.errors.ConfigKeyError` naming the first of ``values`` (a table's keys,
    in the file's order) that is not in ``known``, first, then ``where`` (the table, if given),
    the closest known key, and the known ones.

    >>> check_keys({"episods": 6}, ("episodes", "seeds"), "[experiment]")
    Traceback (most recent call last):
    ...
    skidnav.errors.ConfigKeyError: unknown key 'episods' in [experiment] (did you mean \
'episodes'? expected one of episodes, seeds)
    """
    allowed = tuple(known)
    for key in values:
        if key not in allowed:
            close = difflib.get_close_matches(str(key), allowed, n=1)
            guess = f"did you mean {close[0]!r}? " if close else ""
            raise ConfigKeyError(
                f"unknown key {shown(key)}",
                (where,) if where else (),
                f"{guess}expected one of {', '.join(allowed)}",
            )


def check_types(cls: type, values: Mapping[str, Any], where: str) -> None:
    """ConfigError ``"expected KEY to be …, got … in {where}"`` for the first of ``values`` whose
    field of the dataclass ``cls`` is annotated ``bool``, ``int``, ``float`` or ``str`` (or a
    union of them, with None or not) and that is not of that type: a bool is neither an integer
    nor a number, an integer is a number. Fields of other types are left to the class.

    >>> @dataclasses.dataclass
    ... class Link:
    ...     port: int = 5757
    ...     lockstep: bool = False
    >>> check_types(Link, {"port": 6000, "lockstep": "yes"}, "[tcp]")
    Traceback (most recent call last):
    ...
    skidnav.errors.ConfigError: expected lockstep to be true or false, got 'yes' in [tcp]
    """
    hints = typing.get_type_hints(cls)
    for key, value in values.items():
        kinds = _simple_kinds(hints.get(key))
        if kinds and not any(_is_kind(value, kind) for kind in kinds):
            expected = " or ".join(_KINDS[kind] for kind in kinds if kind in _KINDS)
            problem = f"expected {key} to be {expected}, got {shown(value)}"
            raise ConfigError(problem, (where,) if where else ())


def _simple_kinds(hint: Any) -> tuple[type, ...]:
    """The :data:`_KINDS` an annotation allows, with ``NoneType`` if it allows None too (a
    JSON ``null``; TOML has none); () if it allows anything else."""
    if hint in _KINDS:
        return (hint,)
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        kinds = typing.get_args(hint)
        if all(kind in _KINDS or kind is type(None) for kind in kinds):
            return kinds
    return ()


def _is_kind(value: Any, kind: type) -> bool:
    if kind is type(None):
        return value is None
    if kind is bool or isinstance(value, bool):
        return kind is bool and isinstance(value, bool)
    if kind is float:
        return isinstance(value, int | float)
    return isinstance(value, kind)


def build_dataclass(cls: type[T], value: Any, where: str) -> T:
    """The dataclass ``cls`` built from a TOML table of its fields (each key one field, of the
    field's type as :func:`check_types` checks it; the class validates the values on
    construction); a one-line UserError, what is wrong first and ``where`` after it, for a
    value that is not a table, an unknown key, a value of the wrong type, or a value the class
    refuses (ValueError or TypeError)."""
    values = table(value, where)
    check_keys(values, (f.name for f in dataclasses.fields(cls)), where)  # type: ignore[arg-type]
    check_types(cls, values, where)
    try:
        return cls(**values)
    except (ValueError, TypeError) as error:
        raise within(error, where) from None


def resolve_path(value: str, folder: Path) -> Path:
    """The absolute, resolved path of ``value``, a path written in a config file whose folder is
    ``folder`` (an absolute ``value`` stays where it points)."""
    return (folder / value).resolve()


def toml_value(value: Any) -> str:
    """A TOML literal of a scalar, list or flat dict (what configs hold).

    >>> toml_value({"alpha": 0.5, "mode": "sample", "steps": [1, 2], "on": True})
    '{ alpha = 0.5, mode = "sample", steps = [1, 2], on = true }'
    """
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        return repr(value) if math.isfinite(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, str):
        return json.dumps(value)  # a JSON string is a TOML basic string
    if isinstance(value, list | tuple):
        return "[" + ", ".join(toml_value(item) for item in value) + "]"
    if isinstance(value, dict):
        items = ", ".join(f"{toml_key(key)} = {toml_value(item)}" for key, item in value.items())
        return "{ " + items + " }" if items else "{}"
    raise TypeError(f"expected a TOML scalar, list or table, got {value!r}")


def toml_key(key: str) -> str:
    """A TOML key: bare when it may be, else quoted."""
    return key if _BARE_KEY.match(key) else json.dumps(key)


def toml_document(document: Mapping[str, Any]) -> str:
    """The TOML text of a config ``document``: its top-level values first, then each table
    ``[name]`` and each array of tables ``[[name]]`` (a list of dicts), in the document's order;
    a table's own tables inline.

    >>> print(toml_document({"kind": "x", "run": {"seeds": 2}, "agents": [{"name": "a"}]}))
    kind = "x"
    <BLANKLINE>
    [run]
    seeds = 2
    <BLANKLINE>
    [[agents]]
    name = "a"
    <BLANKLINE>
    """
    lines = [f"{toml_key(k)} = {toml_value(v)}" for k, v in document.items() if not _is_table(v)]
    for name, value in document.items():
        tables = [value] if isinstance(value, dict) else value if _is_table(value) else []
        header = f"[{toml_key(name)}]" if isinstance(value, dict) else f"[[{toml_key(name)}]]"
        for each in tables:
            lines += ["", header, *(f"{toml_key(k)} = {toml_value(v)}" for k, v in each.items())]
    return "\n".join(lines) + "\n"


def _is_table(value: Any) -> bool:
    """A table or a non-empty array of tables (written under a header of its own)."""
    is_array = isinstance(value, list) and bool(value)
    return isinstance(value, dict) or (is_array and all(isinstance(v, dict) for v in value))

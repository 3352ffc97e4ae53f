"""Helpers of the commands' settings objects (frozen dataclasses such as
:class:`~seds_casadi.app.play.PlayConfig`): checked integers, names from a list, and a settings
object with keyword overrides."""

from __future__ import annotations

import dataclasses
import operator
from typing import TypeVar

C = TypeVar("C")


def whole_number(name: str, value, minimum: int) -> int:
    """``value`` as an int of at least ``minimum``, else ``ValueError`` naming the setting."""
    try:
        if isinstance(value, bool):
            raise TypeError
        v = operator.index(value)
    except TypeError:
        raise ValueError(f"{name} must be a whole number, got {value!r}") from None
    if v < minimum:
        raise ValueError(f"{name} must be at least {minimum}, got {value}")
    return v


def names_tuple(what: str, values, valid=None) -> tuple[str, ...]:
    """``values`` (one name or several) as a non-empty tuple of strings, each among ``valid``
    when given."""
    out = (values,) if isinstance(values, str) else tuple(values)
    if not out:
        raise ValueError(f"give at least one {what}")
    for v in out:
        if valid is not None and v not in valid:
            raise ValueError(f"unknown {what} {v!r}; valid: {', '.join(valid)}")
    return out


def with_overrides(cls: type[C], config: C | None, overrides: dict) -> C:
    """``config`` (default: ``cls()``) with the settings in ``overrides`` replaced; a setting
    that does not exist is a ``TypeError`` listing the valid ones."""
    if config is None:
        config = cls()
    elif not isinstance(config, cls):
        raise TypeError(f"config must be a {cls.__name__}, got {type(config).__name__}; "
                        f"give settings as keywords or as {cls.__name__}(...)")
    if not overrides:
        return config
    names = [f.name for f in dataclasses.fields(cls)]
    bad = [k for k in overrides if k not in names]
    if bad:
        raise TypeError(f"{cls.__name__} has no setting {bad[0]!r}; valid: {', '.join(names)}")
    return dataclasses.replace(config, **overrides)

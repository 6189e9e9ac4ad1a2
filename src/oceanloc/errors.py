"""Exceptions for user errors.

Anything a user can cause (a bad scenario file, an impossible parameter, an unreadable log) raises an
:class:`OceanlocError` subclass with a message that names the file, line or field. The CLI prints
these messages without a traceback; anything else is a bug.
"""

from __future__ import annotations


class OceanlocError(Exception):
    """Base class of errors caused by user input."""


class ConfigError(OceanlocError, ValueError):
    """A scenario or option value is missing, malformed or out of range."""


class ArgumentError(ConfigError):
    """An argument of a public function is malformed (shape, NaN, infinity), out of its allowed range or
    too large to allocate; the message names the argument and the range."""


class DataError(OceanlocError, ValueError):
    """An input data file cannot be read or holds no usable records."""

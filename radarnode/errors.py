"""One error hierarchy for the whole package.

Every message names the input (file, field or signal), the offending value and
what would have been allowed, so a user can fix the input without reading code.
"""

from __future__ import annotations


class RadarnodeError(Exception):
    """Base class of every error radarnode raises on purpose."""


class FieldError(RadarnodeError, ValueError):
    """A configuration value is out of its allowed domain.

    Raised by the frozen configuration dataclasses; loaders add the file name,
    the path of the field and its line and re-raise it as a ``ScenarioError``.
    """

    def __init__(self, field: str, value: object, allowed: str) -> None:
        self.field = field
        self.value = value
        self.allowed = allowed
        super().__init__(f"field '{field}': value {value!r} is not allowed; expected {allowed}")


class ScenarioError(RadarnodeError, ValueError):
    """A scenario file cannot be used as written."""


class ConfigError(RadarnodeError, ValueError):
    """A programmatic configuration (CLI option, preset override) is invalid."""


class WireError(RadarnodeError):
    """A DBC file or a CAN frame does not match what the protocol requires."""

"""The one exception hierarchy of usarsim.

Every message says what was wrong, the value received, what is allowed and,
where it helps, where to change it.
"""

from __future__ import annotations


class UsarsimError(Exception):
    """Base class of every error raised on purpose by usarsim."""


class ConfigError(UsarsimError):
    """A world, robot or plugin configuration is invalid.

    ``path`` is the file, ``key`` the dotted key path inside it.
    """

    def __init__(self, message: str, *, path: str | None = None, key: str | None = None):
        self.path = path
        self.key = key
        where = ""
        if path:
            where += f"{path}: "
        if key:
            where += f"{key}: "
        super().__init__(where + message)
        self.message = message


class ProtocolError(UsarsimError):
    """A line received from a client cannot be understood."""


class LineTooLongError(ProtocolError):
    """A client sent a line longer than the configured maximum."""


class PluginNotFoundError(UsarsimError, KeyError):
    """No plugin is registered under the requested name."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class PhysicsError(UsarsimError):
    """The physics became unstable (NaN, infinite or absurd state)."""


class SimulationError(UsarsimError):
    """A request to the simulation cannot be carried out (unknown robot class, bad pose...)."""


class SimulationStopped(SimulationError):
    """A request the simulation will never carry out: it has stopped, or is stopping (the
    server is shutting down, or the simulation stopped on an error)."""

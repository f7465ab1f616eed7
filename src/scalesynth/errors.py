"""Exception hierarchy. Every error a user can cause is a ScalesynthError; the CLI maps it to exit code 2."""


class ScalesynthError(Exception):
    """Base class for errors caused by bad input (config, flag, value, design)."""

    exit_code = 2


class ConfigError(ScalesynthError):
    """A config file or override is missing, malformed or invalid; the message names the field."""


class UnknownMechanism(ScalesynthError):
    """The requested mechanism is not registered."""


class InvalidParameter(ScalesynthError):
    """A mechanism parameter is unknown or has a physically invalid value."""


class InvalidPose(ScalesynthError):
    """A pose or joint-input vector is malformed."""


class RunError(ScalesynthError):
    """A run failed for a reason other than bad input (I/O, interrupted worker); exit code 1."""

    exit_code = 1

"""Typed exceptions shared by the library and its command-line entry points."""


class ConfigError(ValueError):
    """A configuration file or value is missing, malformed or out of range.

    The message names the file and the key at fault, so a command-line entry point can print it
    as one line and exit with code 2.
    """

"""Errors raised on bad user input: each message names the file, key, value and what is allowed."""


class ScenarioError(ValueError):
    """A scenario (TOML) or configuration value that cannot be used."""

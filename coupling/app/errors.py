"""The error of a bad configuration (:mod:`coupling.app.config`,
:mod:`coupling.app.equation_keys`)."""
from __future__ import annotations

__all__ = ["ConfigError"]


class ConfigError(ValueError):
    """A configuration error; the message names the key and the fix."""

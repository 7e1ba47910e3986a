"""Exceptions for mistakes a user can fix.

The CLI prints a :class:`DrapeError` as one message (no traceback) and exits with status 2; any
other exception is a bug in drape and keeps its traceback.
"""

from __future__ import annotations


class DrapeError(Exception):
    """A user-facing error: the message says what is wrong and what to do about it.

    Raised in a torch DataLoader worker, it reaches the main process as the same class made again
    from the worker's whole traceback text ("Caught X in DataLoader worker process N. Original
    Traceback ..."): the message is then the original one, so the CLI still prints one line.
    """

    def __init__(self, *args):
        if len(args) == 1 and isinstance(args[0], str):
            args = (_unwrapped(args[0], type(self)),)
        super().__init__(*args)


_WORKER_TRACEBACK = "\nOriginal Traceback (most recent call last):"


def _unwrapped(message: str, cls: type) -> str:
    """The original message of ``cls`` inside a traceback text that torch's ``ExceptionWrapper``
    wrapped around it (``message`` itself when it is not one)."""
    if not (message.startswith("Caught ") and _WORKER_TRACEBACK in message):
        return message
    for name in (f"{cls.__module__}.{cls.__qualname__}: ", f"{cls.__qualname__}: "):
        k = message.rfind(name)
        if k >= 0:
            return message[k + len(name):].strip()
    return message


class ConfigError(DrapeError, ValueError):
    """A configuration file or value that is malformed, unknown or out of range."""


class InputError(DrapeError, ValueError):
    """An array or file given to drape that has the wrong shape, values or format."""


class SimulationError(DrapeError, RuntimeError):
    """A simulation that cannot go on (e.g. contact buffers that keep overflowing)."""


class MissingDependencyError(DrapeError, ImportError):
    """An optional dependency that the requested feature needs is not installed."""


def require(module: str, feature: str, extra: str | None = None):
    """Import ``module`` or raise :class:`MissingDependencyError` saying how to install it."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as exc:
        hint = f"pip install 'drape[{extra}]'" if extra else f"pip install {module.split('.')[0]}"
        raise MissingDependencyError(
            f"{feature} needs the Python package '{module}', which is not installed ({exc}). "
            f"Install it with: {hint}"
        ) from exc

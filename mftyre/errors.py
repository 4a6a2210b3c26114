"""Exceptions raised by mftyre. Every message says what was wrong and what was expected.

Messages that name a remedy name it in the caller's language: keyword arguments from Python, command-line options
within :func:`speaking_cli` (the command line runs every command in it); :func:`spelled` picks the spelling.
"""
import contextlib
import contextvars

#: "python" (keyword arguments) or "cli" (command-line options): how messages spell remedies.
_SPELLING: contextvars.ContextVar[str] = contextvars.ContextVar("mftyre_spelling", default="python")


@contextlib.contextmanager
def speaking_cli():
    """Within this block messages name command-line options (``--units SA=deg``) instead of keyword arguments
    (``units={'SA': 'deg'}``); thread- and task-safe (a context variable)."""
    token = _SPELLING.set("cli")
    try:
        yield
    finally:
        _SPELLING.reset(token)


def speaking() -> str:
    """The current spelling of remedies: ``"python"`` or ``"cli"``."""
    return _SPELLING.get()


def spelled(python: str, cli: str) -> str:
    """``python`` or ``cli``, whichever language the caller speaks (see :func:`speaking_cli`)."""
    return cli if _SPELLING.get() == "cli" else python


class MFTyreError(Exception):
    """Base class of all mftyre errors."""


class TirError(MFTyreError):
    """A .tir property file is malformed or holds an invalid value (names file, line and parameter)."""


class DataError(MFTyreError):
    """Measured data are malformed (names file, line/column and the reason)."""


class ModelInputError(MFTyreError, ValueError):
    """An input passed to the model is invalid (NaN, non-positive pressure, bad shape...)."""


class PressureFactorWarning(UserWarning):
    """The model is used at an inflation pressure where one of the file's pressure factors (e.g. 1 + PPY1 dpi of
    the cornering stiffness) has changed sign, although the file may declare the pressure valid."""


class LoadFactorWarning(UserWarning):
    """A slip stiffness of the file's Magic Formula changes sign inside its load range FZMIN..FZMAX (e.g. K_xk =
    Fz (PKX1 + PKX2 dfz) exp(PKX3 dfz) with PKX2 < 0): above that load the steady-state tyre pushes along the slip,
    and a dynamic tyre model rolling freely there grows (SWIFT)."""


class TurnSlipWarning(UserWarning):
    """Turn slip is switched on for a file whose Magic Formula turn-slip moment pushes the contact patch along its
    yaw rate at some load (SWIFT: the belt yaw and camber modes can grow)."""


class ReferenceValueWarning(UserWarning):
    """:func:`mftyre.compat.mfeval` returns the reference evaluator's value where no tyre has it, or where the model
    itself refuses the input (beyond the limits of :mod:`mftyre.inputs`): the message names the input and what."""


class InputClippedWarning(UserWarning):
    """Inputs outside the .tir ranges were saturated to them (``limits=True``); the message names each such input,
    its range and how many points."""

"""Exceptions raised by mftyre. Every message says what was wrong and what was expected."""


class MFTyreError(Exception):
    """Base class of all mftyre errors."""


class TirError(MFTyreError):
    """A .tir property file is malformed or holds an invalid value (names file, line and parameter)."""


class DataError(MFTyreError):
    """Measured data are malformed (names file, line/column and the reason)."""


class ModelInputError(MFTyreError, ValueError):
    """An input passed to the model is invalid (NaN, non-positive pressure, bad shape...)."""


class InputClippedWarning(UserWarning):
    """Inputs outside the .tir ranges were saturated to them (``limits=True``); the message names each such input,
    its range and how many points."""

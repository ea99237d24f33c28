"""Exceptions raised by bipolar.

Every error of the library crates and every rejected input becomes one of these, with the
library's own message. Bad input belongs to the ``ValueError`` family (``InputError`` and its
subclasses); wrong types and dtypes are also ``TypeError``; indices out of range also
``IndexError``; files the operating system cannot read or write are ``OSError``.
"""

from __future__ import annotations

__all__ = [
    "BipolarError",
    "InputError",
    "InputTypeError",
    "IndexOutOfRangeError",
    "FileFormatError",
    "NoDescriptorPointsError",
    "FileError",
    "LandmarksNotFoundError",
    "ComputationError",
    "TemplateSettingsError",
]


class BipolarError(Exception):
    """Base class of every exception raised by bipolar."""


class InputError(BipolarError, ValueError):
    """Bad input: a shape, a value, an option, a mesh or a set of points the library refuses."""


class InputTypeError(InputError, TypeError):
    """An argument of the wrong type or dtype (e.g. a float array where indices are expected)."""


class IndexOutOfRangeError(InputError, IndexError):
    """A vertex, face or point index outside its array."""


class FileFormatError(InputError):
    """A file whose content is malformed, unsupported or of an unknown format."""


class NoDescriptorPointsError(InputError):
    """The descriptor would be empty (the message says why, e.g. no level curves cross)."""


class FileError(BipolarError, OSError):
    """The operating system could not read or write a file."""


class LandmarksNotFoundError(BipolarError):
    """Landmark detection found no face-like configuration on the mesh."""


class ComputationError(BipolarError, RuntimeError):
    """A numerical step failed (e.g. a sparse factorisation of a degenerate mesh)."""


class TemplateSettingsError(InputError):
    """A face template made with other settings than the ones it is compared with (the message
    gives both)."""

"""The exceptions of curvefit."""

from __future__ import annotations

from typing import Optional

__all__ = ["InputError", "InternalError"]


class InputError(ValueError):
    """Bad input: the problem's field at fault, its index, and what is wrong.

    The same error, in the same words, as the command line's ``error: {field}: {message}``
    for the same problem.

    Attributes:
        field: path of the offending field, with indices (``"points[3]"``,
            ``"constraint.radii[2]"``, ``"tangents[1].direction"``); ``""`` when the problem as
            a whole is wrong.
        index: the first index in ``field`` (the data point, bound piece or knot at fault), or
            ``None``.
        message: what is wrong, in the user's words.
    """

    def __init__(self, field: str, index: Optional[int], message: str) -> None:
        self.field = field
        self.index = index
        self.message = message
        super().__init__(f"{field}: {message}" if field else message)

    def __reduce__(self):
        # Exceptions pickle their ``args``; this one is rebuilt from its three parts (results
        # of refine_many travel between processes, e.g. from Dask workers).
        return (type(self), (self.field, self.index, self.message))

    def __repr__(self) -> str:
        return f"InputError(field={self.field!r}, index={self.index!r}, message={self.message!r})"


class InternalError(RuntimeError):
    """A bug in curvefit: the solver panicked. Nothing was returned; please report the problem."""

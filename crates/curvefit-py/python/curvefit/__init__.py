"""curvefit: variational curve refinement and constrained spline interpolation, from Python.

One function per subcommand of the ``curvefit`` command line — :func:`refine`, :func:`strip`,
:func:`scheme`, :func:`surface`, :func:`natural` — taking the JSON problem's fields as keyword
arguments (numpy arrays wherever the JSON has arrays, dicts for its objects), so that
``curvefit.refine(**json.load(open(f)))`` is exactly ``curvefit refine f``: same names,
defaults, validation, messages and results. Results are objects whose attributes are the JSON
result's fields (arrays as numpy arrays). :func:`refine_many` solves a list of problems in
parallel. Bad input raises :class:`InputError` (a ``ValueError``) naming the field and index.

Example::

    import numpy as np, curvefit
    th = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    q = np.column_stack([np.cos(th), np.sin(th)])
    r = curvefit.refine(q, closed=True, k=7, radii=np.full(12, 0.05))
    r.points.shape, r.energy, r.kkt_residual      # ((96, 2), ..., ≤ 1e-9)

Every field is documented in ``help(curvefit.refine)`` (and the others) and in the project's
docs/input.md; :func:`schema` gives each problem's JSON Schema.
"""

from __future__ import annotations

import json as _json
from typing import Any, Dict

from . import _curvefit, _results
from ._api import natural, refine, refine_many, scheme, strip, surface
from ._errors import InputError, InternalError
from ._results import (
    ExtraKnot,
    NaturalLevel,
    NaturalResult,
    PolygonResult,
    RefineIterations,
    RefineResult,
    SchemeResult,
    SchemeRule,
    StripResult,
    SurfaceResult,
    SurfaceRule,
)

__version__: str = _curvefit.__version__

SUBCOMMANDS = ("refine", "strip", "scheme", "surface", "natural")


def schema(subcommand: str) -> Dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a subcommand's problem, as ``curvefit schema
    SUBCOMMAND`` prints it: every field with its type, default and meaning."""
    return _json.loads(_curvefit.schema(subcommand))


__all__ = [
    "refine",
    "refine_many",
    "strip",
    "scheme",
    "surface",
    "natural",
    "schema",
    "InputError",
    "InternalError",
    "SUBCOMMANDS",
    "__version__",
]
# The result classes, listed once in their module (the form type checkers follow).
__all__ += _results.__all__

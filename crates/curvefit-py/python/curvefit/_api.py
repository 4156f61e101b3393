"""One function per subcommand of the ``curvefit`` command line.

Each takes the JSON problem's fields as keyword arguments — same names, defaults, validation
and meaning as the command line — so ``curvefit.refine(**json.load(open(f)))`` is
``curvefit refine f``. Wherever the JSON has an array, a numpy array (any dtype that holds
numbers, any memory layout), a list or a tuple will do; nested objects are dicts. Bad input
raises :class:`curvefit.InputError` with the command line's field, index and message.
"""

from __future__ import annotations

import numbers
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _curvefit
from ._errors import InputError, InternalError
from ._results import NaturalResult, RefineResult, SchemeResult, StripResult, SurfaceResult

__all__ = ["refine", "refine_many", "strip", "scheme", "surface", "natural"]

ArrayLike = Any


class _FromPoints:
    """Default of ``surface``'s ``rows`` and ``cols``: taken from a ``(rows, cols, d)`` array."""

    def __repr__(self) -> str:
        return "<from a (rows, cols, d) points array>"


_FROM_POINTS: Any = _FromPoints()

# The JSON defaults, as the signatures show them (tests check them against the JSON Schema
# of each problem, which the Rust types generate). Never mutated.
_INTERPOLATE = {"type": "interpolate"}
_NATURAL = {"type": "natural"}
_SCHEME = {"points": 4, "arity": 2}


def _renamed(e: InputError, renames: Mapping[str, str]) -> InputError:
    """The error with a field written through a convenience keyword named by that keyword; a
    keyword that stands for the whole field (``bc_type``, one number for ``radii`` or
    ``weights``: listed in ``renames`` with a trailing ``"="``) is named without an index."""
    for prefix, name in renames.items():
        if e.field == prefix or e.field.startswith(prefix + "[") or e.field.startswith(prefix + "."):
            if name.endswith("="):
                return InputError(name[:-1], None, e.message)
            return InputError(name + e.field[len(prefix):], e.index, e.message)
    return e


def _ends(bc_type: Any, periodic: str, field: str = "bc_type") -> List[Tuple[Any, ...]]:
    """scipy's ``bc_type`` as [start, end], each ("natural",) or ("slope", value);
    ``periodic`` says what the caller offers instead of ``"periodic"``."""
    if isinstance(bc_type, str):
        if bc_type == "natural":
            return [("natural",), ("natural",)]
        if bc_type == "clamped":
            return [("slope", 0.0), ("slope", 0.0)]
        if bc_type == "periodic":
            raise InputError(field, None, f'"periodic" is not an end condition here: {periodic}')
        raise InputError(
            field,
            None,
            f'{bc_type!r} is not supported: use "natural", "clamped" or '
            "((1, start_derivative), (1, end_derivative))",
        )
    try:
        ends = list(bc_type)
    except TypeError:
        ends = []
    if len(ends) != 2:
        raise InputError(
            field,
            None,
            'must be "natural", "clamped" or a pair ((order, value), (order, value))',
        )
    out: List[Tuple[Any, ...]] = []
    for i, end in enumerate(ends):
        try:
            order, value = end
        except (TypeError, ValueError):
            raise InputError(
                f"{field}[{i}]", i, "must be a pair (order, value): (1, derivative) or (2, 0)"
            ) from None
        if order == 1:
            out.append(("slope", value))
        elif order == 2 and np.all(np.asarray(value) == 0):
            out.append(("natural",))
        else:
            raise InputError(
                f"{field}[{i}]",
                i,
                "must be (1, derivative) or (2, 0) (a natural end); other end conditions are not supported",
            )
    return out


def _per_point(value: Any, points: Any) -> Any:
    """``radii=r`` / ``weights=w`` given as one number: that number for every point (numpy's
    broadcasting of a scalar), when the points' count can be read; anything else as given, for
    the contract's own validation (a bool is not a number there)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.ndarray)):
        return value
    if np.ndim(value) != 0:
        return value
    try:
        n = len(points)
    except TypeError:
        return value
    return np.full(n, float(value))


def _refine_convenience(p: Dict[str, Any]) -> Dict[str, str]:
    """Turns ``radii=``, ``weights=`` and ``bc_type=`` in the problem ``p`` into its JSON
    fields (in place); returns the renames for errors."""
    renames: Dict[str, str] = {}
    radii = p.pop("radii", None)
    weights = p.pop("weights", None)
    bc_type = p.pop("bc_type", None)
    if radii is not None and weights is not None:
        raise InputError("weights", None, "give radii (balls) or weights (smoothing), not both")
    for name, value, kind in (("radii", radii, "balls"), ("weights", weights, "smoothing")):
        if value is None:
            continue
        if p.get("constraint", _INTERPOLATE) is not _INTERPOLATE:
            raise InputError(name, None, f"give {name} or constraint, not both")
        per_point = _per_point(value, p.get("points"))
        p["constraint"] = {"type": kind, name: per_point}
        renames[f"constraint.{name}"] = name + ("=" if per_point is not value else "")
    if bc_type is not None:
        if p.get("boundary", _NATURAL) is not _NATURAL:
            raise InputError("bc_type", None, "give bc_type or boundary, not both")
        start, end = _ends(
            bc_type, "a closed curve is closed=True (its first point is not repeated)"
        )
        if start[0] != end[0]:
            raise InputError(
                "bc_type",
                None,
                "refine's ends are both natural or both clamped (a derivative at each end)",
            )
        if start[0] == "natural":
            p["boundary"] = {"type": "natural"}
        else:
            try:
                d = len(p["points"][0])
            except (KeyError, IndexError, TypeError):
                d = 0
            vec = lambda v: np.broadcast_to(np.asarray(v, dtype=np.float64), (d,))  # noqa: E731
            try:
                p["boundary"] = {"type": "clamped", "start": vec(start[1]), "end": vec(end[1])}
            except ValueError:
                raise InputError(
                    "bc_type", None, f"the end derivatives must be vectors of the points' dimension {d}"
                ) from None
        renames["boundary"] = "bc_type="
    return renames


def refine(
    points: ArrayLike,
    *,
    closed: bool = False,
    knots: Optional[ArrayLike] = None,
    parametrization: Union[str, Mapping[str, float]] = "centripetal",
    k: int = 3,
    knot_iterations: int = 3,
    levels: int = 0,
    level_k: int = 1,
    constraint: Mapping[str, Any] = _INTERPOLATE,
    tangents: Optional[Sequence[Optional[Mapping[str, Any]]]] = None,
    derivative: str = "bessel",
    boundary: Mapping[str, Any] = _NATURAL,
    solver: str = "exact",
    radii: Optional[ArrayLike] = None,
    weights: Optional[ArrayLike] = None,
    bc_type: Any = None,
    **unknown: Any,
) -> RefineResult:
    """Kersey's variational refinement: the refined polygon p_1 … p_N (k new vertices per span)
    of least discrete energy E (Kersey (2.1)) whose data vertices meet the constraint.

    ``curvefit refine problem.json`` in process: the keyword arguments are the JSON problem's
    fields (docs/input.md, "refine").

    Args:
        points: the data q_1 … q_n, an ``(n, d)`` array (n ≥ 2 open, ≥ 3 closed; consecutive
            points distinct). Required.
        closed: default ``False``. ``True``: a closed curve, the last span runs from q_n back
            to q_1; ``False``: an open curve from q_1 to q_n.
        knots: default ``None``. The data parameters u_1 < … < u_n (open) or u_1 < … < u_{n+1}
            (closed, the last closes the curve); when given, no parametrization is computed.
        parametrization: default ``"centripetal"``. How the data parameters (and the knot
            updates) are computed when ``knots`` is absent: u_1 = 0,
            u_{i+1} = u_i + ‖q_{i+1} − q_i‖^e with e = 0 (``"uniform"``), ½ (``"centripetal"``),
            1 (``"chordal"``) or any e ≥ 0 (``{"exponent": e}``).
        k: default ``3``. New vertices per span in the near-interpolatory step (≥ 1).
        knot_iterations: default ``3``. Knot updates alternating with solves (Algorithm 4.1
            part 1), 0 … 100; 0 solves once on the data parameters.
        levels: default ``0``. Further interpolatory refinement steps (Algorithm 4.1 part 2).
        level_k: default ``1``. New vertices per span in each further step (≥ 1).
        constraint: default ``{"type": "interpolate"}``. What the data vertices p_{i_k} must
            satisfy: ``{"type": "interpolate"}`` (p_{i_k} = q_i), ``{"type": "balls",
            "radii": r}`` (‖p_{i_k} − q_i‖ ≤ r_i, n radii ≥ 0; 0 interpolates the point, a
            radius far beyond the data, e.g. 1e300, leaves it free), ``{"type": "smoothing",
            "weights": w}`` (minimize E + ½ Σ w_i ‖p_{i_k} − q_i‖², n weights ≥ 0) or
            ``{"type": "halfspaces", "sets": [[{"normal": a, "offset": c}, …], …]}``
            (p_{i_k} in every half-space a · x ≤ c of its set).
        tangents: default ``None``. One entry per point, a dict or ``None``: a constraint on
            the derivative Df at the data vertex — ``{"type": "ball", "center": v,
            "radius": r}``, ``{"type": "wedge", "direction": a, "half_angle": θ}`` (θ in
            [0, π/2)), ``{"type": "tension", "radius": r}`` (‖Df‖ ≤ r) or
            ``{"type": "halfspaces", "halfspaces": [{"normal": a, "offset": c}, …]}``.
        derivative: default ``"bessel"``. The rule for Df at a vertex: ``"bessel"`` (the
            derivative of the quadratic through p_{i−1}, p_i, p_{i+1}) or ``"average"``
            (Kersey (2.2)).
        boundary: default ``{"type": "natural"}``. End conditions of an open curve:
            ``{"type": "natural"}``, ``{"type": "clamped", "start": v1, "end": vn}``
            (Df(t_1) = v1, Df(t_N) = vn) or ``{"type": "near_clamped", "start": v1,
            "end": vn, "radius": r}``.
        solver: default ``"exact"``. ``"exact"``: the exact optimum with a KKT certificate;
            ``"paper"``: Kersey's multiplier iteration (approximate).

    Convenience keywords (each one way to say a JSON field; not together with that field):
        radii: ``radii=r`` is ``constraint={"type": "balls", "radii": r}``; one number is that
            radius for every point.
        weights: ``weights=w`` is ``constraint={"type": "smoothing", "weights": w}``; one
            number is that weight for every point.
        bc_type: scipy's spelling of ``boundary``: ``"natural"``; ``"clamped"`` (zero end
            derivatives); ``((1, v1), (1, vn))`` (``boundary={"type": "clamped", "start": v1,
            "end": vn}``); ``((2, 0), (2, 0))`` (natural).

    Returns:
        :class:`RefineResult`: ``points`` ``(N, d)``, ``knots``, ``data_vertex``, ``energy``,
        ``multipliers``, ``active``, ``kkt_residual``, ``iterations``.

    Raises:
        InputError: bad input, with the command line's field, index and message (a keyword
            not in this list too: the JSON problem has no such field).
    """
    p: Dict[str, Any] = {
        "points": points,
        "closed": closed,
        "knots": knots,
        "parametrization": parametrization,
        "k": k,
        "knot_iterations": knot_iterations,
        "levels": levels,
        "level_k": level_k,
        "constraint": constraint,
        "tangents": tangents,
        "derivative": derivative,
        "boundary": boundary,
        "solver": solver,
    }
    p.update(unknown)
    if radii is not None:
        p["radii"] = radii
    if weights is not None:
        p["weights"] = weights
    if bc_type is not None:
        p["bc_type"] = bc_type
    renames = _refine_convenience(p)
    try:
        return RefineResult(**_curvefit.solve("refine", p))
    except InputError as e:
        raise _renamed(e, renames) from None


def refine_many(
    problems: Sequence[Mapping[str, Any]], threads: Optional[int] = None
) -> List[Union[RefineResult, InputError, InternalError]]:
    """Solves many refinement problems in parallel (Rust threads, the GIL released).

    Args:
        problems: a sequence of problems, each a mapping of :func:`refine`'s keyword arguments
            (the JSON problem's fields, plus the convenience keywords ``radii``, ``weights``,
            ``bc_type``); fields left out take the JSON's defaults.
        threads: number of threads; default ``None``: one per core.

    Returns:
        One entry per problem, in order: its :class:`RefineResult`, or the
        :class:`InputError` that :func:`refine` would raise for it (returned, not raised; an
        :class:`InternalError` where the library panicked).
        ``refine_many(ps)[i]`` equals ``refine(**ps[i])`` field for field.

    Raises:
        TypeError: ``problems`` is one problem (a mapping) instead of a sequence of them.
        ValueError: ``threads`` is not a whole number ≥ 1.
    """
    if isinstance(problems, Mapping):
        # (Iterating a dict gives its keys: each would come back as "not a problem".)
        raise TypeError(
            "refine_many takes a sequence of problems (e.g. a list of dicts); "
            "for one problem call refine(**problem)"
        )
    if threads is not None and (
        isinstance(threads, bool) or not isinstance(threads, numbers.Integral) or threads < 1
    ):
        raise ValueError(f"threads must be at least 1 (or None), not {threads!r}")
    prepared: List[Any] = []
    renames: List[Dict[str, str]] = []
    early: Dict[int, InputError] = {}
    for i, problem in enumerate(problems):
        if not isinstance(problem, Mapping):
            prepared.append(problem)
            renames.append({})
            continue
        p = dict(problem)
        try:
            renames.append(_refine_convenience(p))
        except InputError as e:
            early[i] = e
            renames.append({})
        prepared.append(p)
    out: List[Union[RefineResult, InputError, InternalError]] = []
    for i, r in enumerate(_curvefit.solve_many("refine", prepared, threads)):
        if i in early:
            out.append(early[i])
        elif isinstance(r, dict):
            out.append(RefineResult(**r))
        elif isinstance(r, InputError):
            out.append(_renamed(r, renames[i]))
        elif isinstance(r, InternalError):
            out.append(r)
        else:  # pragma: no cover - the module returns nothing else
            raise TypeError(f"unexpected entry {r!r}")
    return out


def strip(
    t: ArrayLike,
    y: ArrayLike,
    *,
    lower: Optional[Mapping[str, Any]] = None,
    upper: Optional[Mapping[str, Any]] = None,
    end_slopes: Optional[Sequence[Optional[float]]] = None,
    bc_type: Any = None,
    **unknown: Any,
) -> StripResult:
    """Best interpolation in a strip (Dontchev–Kolmanovsky): the C² cubic spline f with
    f(t_i) = y_i and lower(t) ≤ f(t) ≤ upper(t) of least ∫f''².

    ``curvefit strip problem.json`` in process (docs/input.md, "strip"). The result is callable
    like ``scipy.interpolate.PPoly``: ``s(x)``, ``s(x, nu)``, ``s.to_ppoly()``.

    Args:
        t: data sites t_1 < … < t_n, n ≥ 2 (|t| < 1e100). Required.
        y: data values, one per site (|y| < 1e100). Required.
        lower: default ``None`` (no bound). The lower bound: ``{"pieces": [[c0, c1, c2, c3],
            …]}`` — one cubic per interval [t_i, t_{i+1}] in s = t − t_i, an ``(n − 1, 4)``
            array (a bound may jump at a site) — or ``{"polyline": [[t, value], …]}`` — a
            continuous polyline covering [t_1, t_n].
        upper: default ``None`` (no bound). The upper bound, in the same forms.
        end_slopes: default ``None``. Prescribed ``[f'(t_1), f'(t_n)]``; ``None`` for an entry
            leaves that end natural (f'' = 0).

    Convenience keyword (one way to say ``end_slopes``; not together with it):
        bc_type: scipy's spelling: ``"natural"``; ``"clamped"`` (zero end slopes); a pair of
            ``(1, slope)`` or ``(2, 0)`` (natural) per end.

    Returns:
        :class:`StripResult`: ``breaks``, ``coefficients`` ``(m, 4)``, ``slopes``,
        ``extra_knots``, ``energy``, ``norm``, ``iterations``, ``gradient_norm``.

    Raises:
        InputError: bad input, with the command line's field, index and message.
    """
    p: Dict[str, Any] = {"t": t, "y": y, "lower": lower, "upper": upper, "end_slopes": end_slopes}
    p.update(unknown)
    renames: Dict[str, str] = {}
    if bc_type is not None:
        if end_slopes is not None:
            raise InputError("bc_type", None, "give bc_type or end_slopes, not both")
        ends = _ends(
            bc_type,
            "the strip's spline is not periodic (its ends are natural or have a given slope)",
        )
        p["end_slopes"] = [None if e[0] == "natural" else e[1] for e in ends]
        renames["end_slopes"] = "bc_type="
    try:
        return StripResult(**_curvefit.solve("strip", p))
    except InputError as e:
        raise _renamed(e, renames) from None


def scheme(
    points: int,
    arity: int,
    *,
    surface: bool = False,
    polygon: Optional[Mapping[str, Any]] = None,
    levels: int = 1,
    **unknown: Any,
) -> SchemeResult:
    """The (2m+2)-point n-ary interpolating rules of Khan et al. as exact rationals, optionally
    their tensor-product masks and their application to a polygon.

    ``curvefit scheme --stencil P --arity N [--surface] [--apply POLYGON.json --levels L]`` in
    process (docs/input.md, "scheme"; the command line's flags are the JSON fields below).

    Args:
        points: the stencil size P = 2m + 2 (even, 2 … 16). Required.
        arity: the arity N (2 … 16). Required.
        surface: default ``False``. Also give the N² tensor-product rules.
        polygon: default ``None``. A polygon to refine: ``{"points": (n, d) array (n ≥ 2),
            "closed": False}`` (``closed`` defaults to ``False``: open, end points kept,
            one-sided end stencils; ``True``: periodic).
        levels: default ``1``. Refinement levels applied to ``polygon``.

    Returns:
        :class:`SchemeResult`: ``arity``, ``points``, ``polygon``, ``rules``,
        ``surface_rules``.

    Raises:
        InputError: bad input, with the command line's field, index and message.
    """
    p: Dict[str, Any] = {
        "points": points,
        "arity": arity,
        "surface": surface,
        "polygon": polygon,
        "levels": levels,
    }
    p.update(unknown)
    return SchemeResult(**_curvefit.solve("scheme", p))


def surface(
    points: ArrayLike,
    rows: int = _FROM_POINTS,
    cols: int = _FROM_POINTS,
    *,
    closed: Sequence[bool] = (False, False),
    scheme: Mapping[str, int] = _SCHEME,
    levels: int = 1,
    **unknown: Any,
) -> SurfaceResult:
    """The tensor-product (2m+2)-point n-ary scheme applied to a regular quad grid (Khan et al.
    §4).

    ``curvefit surface problem.json`` in process (docs/input.md, "surface").

    Args:
        points: the grid, ``rows·cols`` points of dimension 2 or 3, row-major (point (i, j) is
            entry i·cols + j). Required. A ``(rows, cols, d)`` array may stand for it:
            ``rows`` and ``cols`` then come from its shape (given as well, they must agree).
        rows: number of rows (range of i), ≥ 2. Required, unless ``points`` is
            ``(rows, cols, d)``.
        cols: number of columns (range of j), ≥ 2. Required, like ``rows``.
        closed: default ``(False, False)``. [wrap the row index i, wrap the column index j].
        scheme: default ``{"points": 4, "arity": 2}``. The curve scheme applied in each
            direction: ``points`` = P (even, 2 … 16), ``arity`` = N (2 … 16); the default is
            Kobbelt's 4-point scheme.
        levels: default ``1``. Refinement levels.

    Returns:
        :class:`SurfaceResult`: ``rows``, ``cols``, ``closed``, ``levels``, ``points``
        (``(rows·cols, d)``; ``grid`` is ``(rows, cols, d)``), ``quads``.

    Raises:
        InputError: bad input, with the command line's field, index and message.
    """
    shape = np.shape(points) if isinstance(points, np.ndarray) else None
    if shape is not None and len(shape) == 3:
        # A (rows, cols, d) grid: its shape says rows and cols; given as well, they must agree
        # (passed on as a 3-D array, it was refused as "points[0][0]: must be a number").
        for name, given, size in (("rows", rows, shape[0]), ("cols", cols, shape[1])):
            if given is not _FROM_POINTS and not (
                isinstance(given, numbers.Integral) and not isinstance(given, bool) and given == size
            ):
                raise InputError(
                    name,
                    None,
                    f"is {given!r}, but the points array of shape {tuple(shape)} has {size} "
                    f"{name} (leave {name} out to take it from the array)",
                )
        rows, cols = shape[0], shape[1]
        points = points.reshape(shape[0] * shape[1], shape[2])
    p: Dict[str, Any] = {"points": points, "closed": closed, "scheme": scheme, "levels": levels}
    if rows is not _FROM_POINTS:
        p["rows"] = rows
    if cols is not _FROM_POINTS:
        p["cols"] = cols
    p.update(unknown)
    return SurfaceResult(**_curvefit.solve("surface", p))


def natural(points: ArrayLike, *, levels: int = 4, **unknown: Any) -> NaturalResult:
    """Warren–Weimer's natural cubic subdivision on [0, L], the control points at the integers
    0 … L. The points are *control points* of an approximating scheme: the limit curve (a C²
    natural cubic spline) does not pass through them.

    ``curvefit natural problem.json`` in process (docs/input.md, "natural").

    Args:
        points: control points p_0 at the integers 0 … L, an ``(L + 1, d)`` array (≥ 2 points,
            any d ≥ 1, subdivided coordinate by coordinate). Required.
        levels: default ``4``. Rounds of subdivision K.

    Returns:
        :class:`NaturalResult`: ``levels`` (for k = 0 … K: ``level``, ``points``
        ``(2^k L + 1, d)``, ``energy``) and ``limit_energy`` (the exact ∫‖p''‖² of the limit).

    Raises:
        InputError: bad input, with the command line's field, index and message.
    """
    p: Dict[str, Any] = {"points": points, "levels": levels}
    p.update(unknown)
    return NaturalResult(**_curvefit.solve("natural", p))

"""Result objects: the JSON result's fields as attributes, arrays as numpy arrays.

Every result has ``to_dict()``, the JSON result as plain Python values (lists, floats, ints,
strings), equal field by field to what ``curvefit SUBCOMMAND problem.json`` prints. Results are
plain Python objects holding numpy arrays: they pickle (for multiprocessing and Dask) and
compare by their fields' values with ``to_dict()``.
"""

from __future__ import annotations

from typing import Any, Dict, List, NamedTuple, Optional, Tuple

import numpy as np

__all__ = [
    "RefineResult",
    "RefineIterations",
    "StripResult",
    "ExtraKnot",
    "SchemeResult",
    "SchemeRule",
    "SurfaceRule",
    "PolygonResult",
    "SurfaceResult",
    "NaturalResult",
    "NaturalLevel",
]


def _plain(v: Any) -> Any:
    """A field as JSON-compatible Python values."""
    if isinstance(v, np.ndarray):
        return v.tolist()
    if hasattr(v, "to_dict"):
        return v.to_dict()
    if isinstance(v, tuple) and hasattr(v, "_asdict"):
        return {k: _plain(x) for k, x in v._asdict().items()}
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    if isinstance(v, (np.floating, np.integer, np.bool_)):
        return v.item()
    return v


def _short(v: Any) -> str:
    """A field for a repr: arrays by shape and dtype, long lists by length."""
    if isinstance(v, np.ndarray):
        if v.size <= 6:
            return np.array2string(v, separator=", ", threshold=6).replace("\n", "")
        return f"<{v.dtype} array {v.shape}>"
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list) and len(v) > 3:
        return f"[{len(v)} items]"
    return repr(v)


class _Result:
    """Fields in the JSON's order (``_fields``), a readable repr, ``to_dict()``."""

    _fields: Tuple[str, ...] = ()
    # Fields the repr leaves out (long or secondary); to_dict() has them all.
    _repr_skip: Tuple[str, ...] = ()

    def __init__(self, **fields: Any) -> None:
        for name in self._fields:
            setattr(self, name, fields.pop(name))
        if fields:
            raise TypeError(f"unexpected fields {sorted(fields)}")

    def to_dict(self) -> Dict[str, Any]:
        """The JSON result: every field as plain Python values (lists, floats, ints, str)."""
        out: Dict[str, Any] = {}
        for name in self._fields:
            v = getattr(self, name)
            out[name] = _plain(v)
        return out

    def __repr__(self) -> str:
        parts = [
            f"{name}={_short(getattr(self, name))}"
            for name in self._fields
            if name not in self._repr_skip
        ]
        return f"{type(self).__name__}({', '.join(parts)})"


class RefineIterations(NamedTuple):
    """Iteration counts of a refinement."""

    knot_updates: int
    """Knot updates over all stages."""
    solver: int
    """Inner iterations of the fixed-knot solver over all stages."""
    solves: int
    """Fixed-knot solves over all stages."""


class RefineResult(_Result):
    """The result of :func:`curvefit.refine` (the JSON result of ``curvefit refine``).

    Attributes:
        points: ``(N, d)`` float64, the refined vertices p_1..p_N (a closed curve does not
            repeat p_1).
        knots: ``(N,)`` (open) or ``(N + 1,)`` (closed) float64, the knots the points were
            solved with.
        data_vertex: ``(n,)`` int64, the 0-based index of the vertex attached to each data point.
        energy: E of Kersey (2.1) for ``points`` and ``knots``.
        multipliers: the multipliers of the final solve, one row per data point, in the
            constraint's convention (interpolation: the reaction −(Hp)_{i_k}, d values; balls
            and smoothing: ``[w_i]``; half-spaces: one per half-space). A 2-D float64 array
            when every row has the same length, else a list of 1-D arrays.
        active: ``(n,)`` bool, which data-point constraints are active at the optimum.
        kkt_residual: the relative KKT residual of the final solve (≤ 1e-9 for an exact solve).
        iterations: :class:`RefineIterations` (``knot_updates``, ``solver``, ``solves``).
    """

    _fields = (
        "points",
        "knots",
        "data_vertex",
        "energy",
        "multipliers",
        "active",
        "kkt_residual",
        "iterations",
    )
    _repr_skip = ("knots", "data_vertex", "multipliers", "active")

    points: np.ndarray
    knots: np.ndarray
    data_vertex: np.ndarray
    energy: float
    multipliers: Any
    active: np.ndarray
    kkt_residual: float
    iterations: RefineIterations

    def __init__(self, **fields: Any) -> None:
        fields["iterations"] = RefineIterations(**fields["iterations"])
        super().__init__(**fields)

    def __repr__(self) -> str:
        base = super().__repr__()[:-1]
        return f"{base}, active={int(np.count_nonzero(self.active))} of {len(self.active)})"


class ExtraKnot(NamedTuple):
    """An extra knot of the strip solution: where, and what happens there."""

    t: float
    """Where."""
    kind: str
    """``touch_lower``, ``touch_upper``, ``subarc_start_lower``, ``subarc_end_lower``,
    ``subarc_start_upper`` or ``subarc_end_upper``."""


class StripResult(_Result):
    """The result of :func:`curvefit.strip`: a C² piecewise cubic, callable like
    ``scipy.interpolate.PPoly``.

    ``s(x)`` evaluates it, ``s(x, nu)`` its ``nu``-th derivative (``nu`` = 0…3; higher ones are
    0), at any array of ``x`` (the result has ``x``'s shape). Outside ``[breaks[0],
    breaks[-1]]`` the end pieces are extended (``extrapolate=True``, PPoly's default) or NaN is
    returned (``extrapolate=False``). ``s.to_ppoly()`` is the same function as a scipy ``PPoly``.

    Attributes:
        breaks: ``(m + 1,)`` float64, the breakpoints (data sites and extra knots).
        coefficients: ``(m, 4)`` float64, ``[c0, c1, c2, c3]`` of the cubic on
            ``[breaks[j], breaks[j+1]]`` in ``s = x − breaks[j]`` (ascending powers; PPoly's
            ``c`` is ``coefficients[:, ::-1].T``).
        slopes: ``(n,)`` float64, f'(t_i) at the data sites.
        extra_knots: list of :class:`ExtraKnot` (``t``, ``kind``).
        energy: ∫ f''².
        norm: ‖f''‖ = √energy.
        iterations: outer iterations.
        gradient_norm: the final gradient norm of Φ (Dontchev–Kolmanovsky §3).
    """

    _fields = (
        "breaks",
        "coefficients",
        "slopes",
        "extra_knots",
        "energy",
        "norm",
        "iterations",
        "gradient_norm",
    )
    _repr_skip = ("coefficients", "slopes")

    breaks: np.ndarray
    coefficients: np.ndarray
    slopes: np.ndarray
    extra_knots: List[ExtraKnot]
    energy: float
    norm: float
    iterations: int
    gradient_norm: float

    def __init__(self, **fields: Any) -> None:
        fields["extra_knots"] = [ExtraKnot(t, kind) for t, kind in fields["extra_knots"]]
        super().__init__(**fields)

    def __call__(self, x: Any, nu: int = 0, extrapolate: bool = True) -> np.ndarray:
        """The ``nu``-th derivative at ``x`` (an array of any shape, or a number)."""
        if not isinstance(nu, (int, np.integer)) or isinstance(nu, bool) or nu < 0:
            raise ValueError(f"nu must be a whole number >= 0, got {nu!r}")
        x = np.asarray(x, dtype=np.float64)
        b = self.breaks
        c = self.coefficients
        m = len(c)
        j = np.clip(np.searchsorted(b, x, side="right") - 1, 0, m - 1)
        s = x - b[j]
        c0, c1, c2, c3 = (c[j, i] for i in range(4))
        if nu == 0:
            y = ((c3 * s + c2) * s + c1) * s + c0
        elif nu == 1:
            y = (3.0 * c3 * s + 2.0 * c2) * s + c1
        elif nu == 2:
            y = 6.0 * c3 * s + 2.0 * c2
        elif nu == 3:
            y = 6.0 * c3 + 0.0 * s
        else:
            y = 0.0 * s
        if not extrapolate:
            y = np.where((x < b[0]) | (x > b[-1]), np.nan, y)
        return np.asarray(y)

    def to_ppoly(self):
        """The same piecewise cubic as ``scipy.interpolate.PPoly`` (scipy must be installed)."""
        try:
            from scipy.interpolate import PPoly
        except ImportError as e:  # pragma: no cover - scipy is not a dependency
            raise ImportError("StripResult.to_ppoly() needs scipy: pip install scipy") from e
        return PPoly(np.ascontiguousarray(self.coefficients[:, ::-1].T), self.breaks)


class SchemeRule(_Result):
    """One rule p^{k+1}_{N·i+a} = Σ_l weights[l] · p^k_{i+offsets[l]}.

    Attributes:
        floats: the weights as correctly rounded float64.
        offsets: int64, the offsets −m … m + 1.
        residue: the residue a.
        weights: the exact weights as ``"num/den"`` (``"num"`` for integers).
    """

    _fields = ("floats", "offsets", "residue", "weights")

    floats: np.ndarray
    offsets: np.ndarray
    residue: int
    weights: List[str]


class SurfaceRule(_Result):
    """One tensor-product rule (row-major in (a, b) and in (r, s)).

    Attributes:
        floats: the weights as correctly rounded float64.
        offsets: ``(P², 2)`` int64, the offsets (r, s).
        residue: ``(a, b)``.
        weights: the exact weights as ``"num/den"``.
    """

    _fields = ("floats", "offsets", "residue", "weights")

    floats: np.ndarray
    offsets: np.ndarray
    residue: Tuple[int, int]
    weights: List[str]


class PolygonResult(_Result):
    """The refined polygon of a scheme problem.

    Attributes:
        closed: as in the problem.
        input: ``(n, d)`` float64, the input points.
        levels: levels applied.
        output: ``(m, d)`` float64, the refined points.
    """

    _fields = ("closed", "input", "levels", "output")

    closed: bool
    input: np.ndarray
    levels: int
    output: np.ndarray


class SchemeResult(_Result):
    """The result of :func:`curvefit.scheme`.

    Attributes:
        arity: N.
        points: P (the stencil size).
        polygon: :class:`PolygonResult`, or ``None`` without a polygon.
        rules: N :class:`SchemeRule`, one per residue a = 0 … N − 1.
        surface_rules: N² :class:`SurfaceRule` with ``surface=True``, else ``None``.
    """

    _fields = ("arity", "points", "polygon", "rules", "surface_rules")

    arity: int
    points: int
    polygon: Optional[PolygonResult]
    rules: List[SchemeRule]
    surface_rules: Optional[List[SurfaceRule]]

    def __init__(self, **fields: Any) -> None:
        if fields["polygon"] is not None:
            fields["polygon"] = PolygonResult(**fields["polygon"])
        fields["rules"] = [SchemeRule(**r) for r in fields["rules"]]
        if fields["surface_rules"] is not None:
            fields["surface_rules"] = [SurfaceRule(**r) for r in fields["surface_rules"]]
        super().__init__(**fields)

    def to_dict(self) -> Dict[str, Any]:
        # The JSON has no "polygon" or "surface_rules" when there are none.
        d = super().to_dict()
        return {k: v for k, v in d.items() if v is not None}


class SurfaceResult(_Result):
    """The result of :func:`curvefit.surface`.

    Attributes:
        rows, cols: the refined grid's size.
        closed: ``(closed in i, closed in j)``, as in the problem.
        levels: as in the problem.
        points: ``(rows·cols, d)`` float64, row-major (``grid`` is the ``(rows, cols, d)`` view).
        quads: ``(m, 4)`` int64, 0-based indices of (i, j), (i, j+1), (i+1, j+1), (i+1, j).
    """

    _fields = ("rows", "cols", "closed", "levels", "points", "quads")

    rows: int
    cols: int
    closed: Tuple[bool, bool]
    levels: int
    points: np.ndarray
    quads: np.ndarray

    @property
    def grid(self) -> np.ndarray:
        """``points`` as a ``(rows, cols, d)`` view."""
        return self.points.reshape(self.rows, self.cols, -1)


class NaturalLevel(_Result):
    """One level k of natural subdivision.

    Attributes:
        level: k.
        points: ``(2^k L + 1, d)`` float64, p_k.
        energy: p_kᵀ E_k p_k summed over coordinates.
    """

    _fields = ("level", "points", "energy")

    level: int
    points: np.ndarray
    energy: float


class NaturalResult(_Result):
    """The result of :func:`curvefit.natural`.

    Attributes:
        levels: :class:`NaturalLevel` for k = 0 … K.
        limit_energy: p₀ᵀE₀N₀p₀ summed over coordinates: the exact ∫‖p''‖² of the limit curve
            (Warren–Weimer Theorem 6.4).
    """

    _fields = ("levels", "limit_energy")

    levels: List[NaturalLevel]
    limit_energy: float

    def __init__(self, **fields: Any) -> None:
        fields["levels"] = [NaturalLevel(**lv) for lv in fields["levels"]]
        super().__init__(**fields)

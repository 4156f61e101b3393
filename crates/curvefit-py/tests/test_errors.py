"""Bad input raises curvefit.InputError (a ValueError) with the command line's field, index and
message: each problem below is given to the binary (as JSON on standard input) and to the
package (as keyword arguments), and the two errors must be the same line."""

import json
import math
import pickle
import re

import numpy as np
import pytest

import curvefit
from conftest import cli_error

P = '"points": [[0, 0], [1, 0], [0, 1]]'

CASES = [
    ("refine", f'{{{P}, "closed": false, "boundary": "clamped"}}'),
    ("refine", f'{{{P}, "constraint": "balls"}}'),
    ("refine", f'{{{P}, "constraint": {{"type": "balls"}}}}'),
    ("refine", f'{{{P}, "constraint": {{"type": "balls", "radii": [1, -0.34, 1]}}}}'),
    ("refine", f'{{{P}, "constraint": {{"type": "balls", "radii": [1, 1]}}}}'),
    ("refine", f'{{{P}, "constraint": {{"type": "balls", "radii": [1, "x", 1]}}}}'),
    ("refine", f'{{{P}, "constraint": {{"type": "smoothing", "weights": [1, 1, -2]}}}}'),
    ("refine", f'{{{P}, "constraint": {{"type": "halfspaces", "sets": [[{{"normal": [0, 0], "offset": 1}}], [], []]}}}}'),
    ("refine", f'{{{P}, "constraint": {{"type": "halfspaces", "sets": [[{{"normal": [1, 0]}}], [], []]}}}}'),
    ("refine", f'{{{P}, "tangents": ["wedge", null, null]}}'),
    ("refine", f'{{{P}, "tangents": [null, {{"type": "wedge", "direction": [0, 0], "half_angle": 0.1}}, null]}}'),
    ("refine", f'{{{P}, "tangents": [null, {{"type": "wedge", "direction": [1, 0], "half_angle": 2}}, null]}}'),
    ("refine", f'{{{P}, "parametrization": "centripedal"}}'),
    ("refine", f'{{{P}, "parametrization": 0.5}}'),
    ("refine", f'{{{P}, "parametrization": {{"exponent": -1}}}}'),
    ("refine", f'{{{P}, "parametrization": {{"exponent": 0.5, "x": 1}}}}'),
    ("refine", f'{{{P}, "closed": false, "boundary": {{"type": "clamp"}}}}'),
    ("refine", f'{{{P}, "closed": true, "boundary": {{"type": "clamped", "start": [1, 0], "end": [1, 0]}}}}'),
    ("refine", f'{{{P}, "boundary": {{"type": "clamped", "start": [1], "end": [1, 0]}}}}'),
    ("refine", f'{{{P}, "closed": false, "boundary": {{"type": "near_clamped", "start": [1, 0], "end": [1, 0], "radius": 0.2}}, "tangents": [null, null, {{"type": "tension", "radius": 0.5}}]}}'),
    # Objects with a "type": errors inside keep their path; fields of another type are refused.
    ("refine", f'{{{P}, "constraint": {{"type": "balls", "radii": 0.1}}}}'),
    ("refine", f'{{{P}, "constraint": {{"type": "halfspaces", "sets": [[], [{{"normal": [1, 0], "offset": "x"}}], []]}}}}'),
    ("refine", f'{{{P}, "constraint": {{"type": "interpolate", "radii": [1, 1, 1]}}}}'),
    ("refine", f'{{{P}, "constraint": [1, 2]}}'),
    ("refine", f'{{{P}, "constraint": {{"type": 3}}}}'),
    ("refine", f'{{{P}, "tangents": [null, {{"type": "ball", "center": [1, "x"], "radius": 1}}, null]}}'),
    ("refine", f'{{{P}, "tangents": [{{"type": "tension", "radius": 1, "center": [0, 0]}}, null, null]}}'),
    ("refine", f'{{{P}, "boundary": {{"type": "natural", "start": [1, 0]}}}}'),
    ("refine", f'{{{P}, "k": -1}}'),
    ("refine", f'{{{P}, "k": 1.5}}'),
    ("refine", f'{{{P}, "k": 0}}'),
    ("refine", f'{{{P}, "k": "3"}}'),
    ("refine", f'{{{P}, "levels": 40}}'),
    ("refine", f'{{{P}, "knot_iterations": 101}}'),
    ("refine", f'{{{P}, "closed": "yes"}}'),
    ("refine", f'{{{P}, "knots": [0, 1, 2, "a"]}}'),
    ("refine", f'{{{P}, "knots": [0, 1, 1]}}'),
    ("refine", f'{{{P}, "knots": [0, 1]}}'),
    ("refine", f'{{{P}, "derivative": "central"}}'),
    ("refine", f'{{{P}, "solver": 1}}'),
    ("refine", f'{{{P}, "bogus": 1}}'),
    ("refine", '{"points": [1, 2, 3]}'),
    ("refine", '{"points": [[0, 0], [1]]}'),
    ("refine", '{"points": [[0, 0], [0, 0], [1, 1]]}'),
    ("refine", '{"points": [[], []]}'),
    ("refine", '{"points": [[0, 0]]}'),
    ("refine", '{"points": [[0, 0], [1, 0]], "closed": true}'),
    ("refine", '{"points": {"x": 1}}'),
    ("refine", '{"points": [[0, 0], [1, true]]}'),
    ("strip", '{"t": [0, 1, 2], "y": [0, 1.34, 0], "upper": {"pieces": [[1, 0, 0, 0], [1, 0, 0, 0]]}}'),
    ("strip", '{"t": [0, 1, 2], "y": [0, 1, 0], "upper": {"polyline": [[1, 0, 0]]}}'),
    ("strip", '{"t": [0, 1, 2], "y": [0, 1, 0], "upper": [[1, 0, 0, 0]]}'),
    ("strip", '{"t": [0, 1, 2], "y": [0, 1, 0], "upper": 1}'),
    ("strip", '{"t": [0, 1, 2], "y": [0, 1, 0], "lower": {"pieces": [[0, 0, 0, 0]]}}'),
    ("strip", '{"t": [0, 1, 2], "y": [0, 1, 0], "lower": {"pieces": [[0, 0, 0, 0, 0], [0, 0, 0, 0]]}}'),
    ("strip", '{"t": [0, 1, 2], "y": [0, 1, 0], "lower": {"pieces": [[-1, 0, 0, 0], [2, 0, 0, 0]]}, "upper": {"pieces": [[1, 0, 0, 0], [1, 0, 0, 0]]}}'),
    ("strip", '{"t": [0, 1, 2], "y": [0, 1, 0], "end_slopes": [1]}'),
    ("strip", '{"t": [0, 1, 2], "y": [0, 1, 0], "end_slopes": [1, 2, 3]}'),
    ("strip", '{"t": [0, 1, 1], "y": [0, 1, 0]}'),
    ("strip", '{"t": [0, 1, 2], "y": [0, 1]}'),
    ("strip", '{"t": [0], "y": [0]}'),
    ("strip", '{"t": [0, 1, 2], "y": [0, 1, 0], "lower": {"pieces": [[0, 0, 0, 0], [0, 0, 0, 0]], "polyline": [[0, 0], [2, 0]]}}'),
    ("natural", '{"points": [[0, 0]]}'),
    ("natural", '{"points": [[0, 0], [1]]}'),
    ("natural", '{"points": [[0, 0], [1, 1]], "levels": 40}'),
    ("natural", '{"points": [[0, 0], [1, 1]], "levels": -1}'),
    ("natural", '{"points": [[0, 0], [1, 1e308], [3, 1]]}'),
    ("surface", '{"rows": 2, "cols": 2, "points": [[0, 0], [1, 0], [0, 1], [1, 1]], "scheme": 4}'),
    ("surface", '{"rows": 1, "cols": 2, "points": [[0, 0], [1, 0]]}'),
    ("surface", '{"rows": 2, "cols": 2, "points": [[0, 0], [1, 0], [0, 1]]}'),
    ("surface", '{"rows": 2, "cols": 2, "points": [[0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0], [1, 1, 0, 0]]}'),
    ("surface", '{"rows": 2, "cols": 2, "points": [[0, 0], [1, 0], [0, 1], [1, 1]], "scheme": {"points": 5}}'),
    ("surface", '{"rows": 2, "cols": 2, "points": [[0, 0], [1, 0], [0, 1], [1, 1]], "closed": [true]}'),
    ("surface", '{"rows": 2, "cols": 2, "points": [[0, 0], [1, 0], [0, 1], [1, 1]], "levels": 30}'),
    ("surface", '{"cols": 2, "points": [[0, 0], [1, 0], [0, 1], [1, 1]]}'),
]


def first_index(field):
    m = re.search(r"\[(\d+)\]", field)
    return int(m.group(1)) if m else None


def python_error(sub, text):
    problem = json.loads(text)
    with pytest.raises(curvefit.InputError) as info:
        getattr(curvefit, sub)(**problem)
    return info.value


@pytest.mark.parametrize("sub,text", CASES, ids=[f"{s}-{i}" for i, (s, _) in enumerate(CASES)])
def test_error_equals_the_command_line(sub, text):
    expected = cli_error(sub, text)
    e = python_error(sub, text)
    assert str(e) == expected
    assert isinstance(e, ValueError)
    # The field and message are the line's two parts; the index is the field's first [i].
    if e.field:
        assert expected == f"{e.field}: {e.message}"
    else:
        assert expected == e.message
    assert e.index == first_index(e.field)


def test_every_error_names_a_field_the_problem_has():
    for sub, text in CASES:
        e = python_error(sub, text)
        top = re.split(r"[.\[]", e.field)[0]
        required = e.message.startswith("is required")
        assert top == "" or top in json.loads(text) or top == "bogus" or required, (text, e.field)


def test_a_required_field_left_out_is_named():
    # (serde reports it at the problem itself: the message named no field, and `field` was "".)
    e = python_error("surface", '{"cols": 2, "points": [[0, 0], [1, 0], [0, 1], [1, 1]]}')
    assert (e.field, e.index) == ("rows", None)
    assert str(e) == "rows: is required (this problem has no default for it)"


def test_a_grid_array_and_its_rows_and_cols():
    g = np.arange(4 * 5 * 3, dtype=float).reshape(4, 5, 3)
    whole = curvefit.surface(g).to_dict()
    # Given as well, rows and cols that agree with the array's shape change nothing ...
    assert curvefit.surface(g, rows=4, cols=5).to_dict() == whole
    assert curvefit.surface(g, rows=np.int64(4)).to_dict() == whole
    # ... and ones that do not are refused by name (the array was passed on as it was, and
    # refused as "points[0][0]: must be a number, not an array").
    for kwargs, field in [({"rows": 5, "cols": 4}, "rows"), ({"cols": 4}, "cols"), ({"rows": 4.0}, "rows")]:
        with pytest.raises(curvefit.InputError) as e:
            curvefit.surface(g, **kwargs)
        assert e.value.field == field
        assert "(4, 5, 3)" in e.value.message


def test_errors_pickle():
    e = python_error("refine", CASES[3][1])
    e2 = pickle.loads(pickle.dumps(e))
    assert (e2.field, e2.index, e2.message, str(e2)) == (e.field, e.index, e.message, str(e))
    assert type(e2) is curvefit.InputError


# Python values that JSON cannot express are refused with a field path too.
@pytest.mark.parametrize(
    "kwargs,field",
    [
        ({"points": [[0, 0], [1, math.nan], [0, 1]]}, "points[1][1]"),
        ({"points": np.array([[0, 0], [1, 0], [0, np.inf]])}, "points[2][1]"),
        ({"points": [[0, 0], [1, 0], [0, 1]], "radii": [0.1, np.nan, 0.1]}, "radii[1]"),
        ({"points": [[0, 0], [1, 0], [0, 1]], "knots": [0, 1, complex(2, 1)]}, "knots[2]"),
        ({"points": [[0, 0], [1, 0], [0, 1]], "k": object()}, "k"),
        ({"points": [[0, 0], [1, 0], [0, 1]], "tangents": [None, {1: 2}, None]}, "tangents[1]"),
    ],
)
def test_python_values_without_json(kwargs, field):
    with pytest.raises(curvefit.InputError) as info:
        curvefit.refine(**kwargs)
    assert info.value.field == field, info.value


def test_errors_of_arrays_equal_errors_of_lists():
    bad = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0]])
    with pytest.raises(curvefit.InputError) as a:
        curvefit.refine(bad)
    with pytest.raises(curvefit.InputError) as b:
        curvefit.refine(bad.tolist())
    assert str(a.value) == str(b.value) == "points[2]: coincides with points[1] (consecutive points must differ: zero-length span)"
    with pytest.raises(curvefit.InputError) as c:
        curvefit.strip([0, 1, 2], [0, 1, 0], lower={"pieces": np.zeros((2, 5))})
    assert c.value.field == "lower.pieces[0]"


def test_convenience_keywords_name_themselves():
    q = [[0, 0], [1, 0], [0, 1]]
    with pytest.raises(curvefit.InputError) as e:
        curvefit.refine(q, radii=[0.1, -1, 0.1])
    assert (e.value.field, e.value.index) == ("radii[1]", 1)
    assert e.value.message == cli_error("refine", f'{{{P}, "constraint": {{"type": "balls", "radii": [0.1, -1, 0.1]}}}}').split(": ", 1)[1]
    with pytest.raises(curvefit.InputError) as e:
        curvefit.refine(q, weights=[1, 1])
    assert e.value.field == "weights"
    # One number for every point: its error names the keyword, with no index, in the
    # contract's words for the entry.
    with pytest.raises(curvefit.InputError) as e:
        curvefit.refine(q, radii=-1)
    assert (e.value.field, e.value.index) == ("radii", None)
    assert e.value.message == cli_error("refine", f'{{{P}, "constraint": {{"type": "balls", "radii": [-1, -1, -1]}}}}').split(": ", 1)[1]
    with pytest.raises(curvefit.InputError) as e:
        curvefit.refine(q, weights=float("nan"))
    assert (e.value.field, e.value.index, e.value.message) == ("weights", None, "must be a finite number, not NaN")
    with pytest.raises(curvefit.InputError) as e:
        curvefit.refine(q, radii=True)
    assert e.value.field == "radii"
    with pytest.raises(curvefit.InputError) as e:
        curvefit.refine(q, radii=[1, 1, 1], constraint={"type": "interpolate"})
    assert e.value.field == "radii"
    with pytest.raises(curvefit.InputError) as e:
        curvefit.refine(q, radii=[1, 1, 1], weights=[1, 1, 1])
    assert e.value.field == "weights"
    with pytest.raises(curvefit.InputError) as e:
        curvefit.refine(q, bc_type="periodic")
    assert e.value.field == "bc_type"
    with pytest.raises(curvefit.InputError) as e:
        curvefit.refine(q, bc_type=((1, [1, 0]), (2, 0)))
    assert e.value.field == "bc_type"
    with pytest.raises(curvefit.InputError) as e:
        curvefit.refine(q, closed=True, bc_type="clamped")
    assert e.value.field == "bc_type"
    with pytest.raises(curvefit.InputError) as e:
        curvefit.strip([0, 1, 2], [0, 1, 0], bc_type="clamped", end_slopes=[0, 0])
    assert e.value.field == "bc_type"
    # "periodic" is answered in each function's own terms (the strip has no closed curves).
    with pytest.raises(curvefit.InputError, match="closed=True"):
        curvefit.refine(q, bc_type="periodic")
    with pytest.raises(curvefit.InputError, match="strip's spline is not periodic"):
        curvefit.strip([0, 1, 2], [0, 1, 0], bc_type="periodic")


def test_bad_subcommand_and_threads():
    with pytest.raises(ValueError):
        curvefit._curvefit.solve("bogus", {})
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="threads must be at least 1"):
            curvefit.refine_many([], threads=bad)
    # One problem where a list of them is wanted (iterating it would give its keys).
    with pytest.raises(TypeError, match="sequence of problems"):
        curvefit.refine_many({"points": [[0, 0], [1, 0]]})


def test_a_panic_becomes_an_internal_error():
    """Every call runs the library under a panic guard; its check panics on purpose."""
    with pytest.raises(curvefit.InternalError, match="internal error .a bug in curvefit") as e:
        curvefit._curvefit._panic_guard_check()
    assert "the guard's own check" in str(e.value)
    assert isinstance(e.value, RuntimeError) and not isinstance(e.value, ValueError)

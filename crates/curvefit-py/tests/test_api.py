"""The contract itself: signatures and defaults against the JSON Schema that the Rust types
generate, docstrings that list every field and its default, stubs, reprs."""

import ast
import inspect
import re
import json
import pydoc
from pathlib import Path

import numpy as np
import pytest

import curvefit

FUNCTIONS = {
    "refine": curvefit.refine,
    "strip": curvefit.strip,
    "scheme": curvefit.scheme,
    "surface": curvefit.surface,
    "natural": curvefit.natural,
}
CONVENIENCE = {"radii", "weights", "bc_type"}


@pytest.mark.parametrize("sub", list(FUNCTIONS))
def test_signature_is_the_schema(sub):
    schema = curvefit.schema(sub)
    props = schema["properties"]
    required = set(schema.get("required", []))
    params = inspect.signature(FUNCTIONS[sub]).parameters
    named = [n for n, p in params.items() if p.kind is not inspect.Parameter.VAR_KEYWORD]
    assert set(named) - CONVENIENCE == set(props), "every field is a keyword, and no other"
    for name, field in props.items():
        p = params[name]
        if name in required:
            # Required fields have no default (surface's rows/cols may come from the points).
            assert p.default is inspect.Parameter.empty or sub == "surface", name
            continue
        default = field.get("default", None)
        got = p.default
        if isinstance(got, tuple):
            got = list(got)
        assert json.loads(json.dumps(got)) == default, (name, got, default)


def plain(v):
    return [plain(x) for x in v] if isinstance(v, (list, tuple)) else v


@pytest.mark.parametrize("sub", list(FUNCTIONS))
def test_help_lists_every_field_and_default(sub):
    """help() shows each field as "name: default ``value``. meaning" (value a Python literal
    equal to the schema's default) or "name: ... Required."."""
    text = pydoc.render_doc(FUNCTIONS[sub], renderer=pydoc.plaintext)
    text = " ".join(text.split())
    schema = curvefit.schema(sub)
    for name, field in schema["properties"].items():
        if "default" in field:
            m = re.search(rf"\b{name}: default ``(.+?)``", text)
            assert m, name
            assert plain(ast.literal_eval(m.group(1))) == field["default"], (name, m.group(1))
        else:
            m = re.search(rf"\b{name}: [^:]*?Required", text)
            assert m, name


def test_stubs_and_marker_are_installed():
    pkg = Path(curvefit.__file__).parent
    assert (pkg / "py.typed").exists()
    assert (pkg / "_curvefit.pyi").exists()
    stub = (pkg / "_curvefit.pyi").read_text()
    for name in ("def solve(", "def solve_many(", "def schema("):
        assert name in stub


def test_reprs_are_readable():
    r = curvefit.refine([[0, 0], [1, 0], [1, 1], [0, 1]], closed=True)
    text = repr(r)
    assert text.startswith("RefineResult(points=<float64 array (16, 2)>")
    assert "kkt_residual=" in text and "active=4 of 4" in text and len(text) < 300
    s = curvefit.strip([0, 1, 2], [0, 1, 0])
    assert repr(s).startswith("StripResult(breaks=[0., 1., 2.]")
    e = curvefit.InputError("points[2]", 2, "bad")
    assert repr(e) == "InputError(field='points[2]', index=2, message='bad')" and str(e) == "points[2]: bad"


def test_one_radius_or_weight_for_every_point():
    """``radii=r`` and ``weights=w`` given as one number (a Python or numpy scalar) are that
    number at every point: the same answer as the array written out."""
    q = np.array([[0, 0], [1, 0.2], [0.4, 1], [1.3, 1.5], [2, 0.5]])
    for kw, value in (("radii", 0.1), ("radii", np.float32(0.25)), ("weights", 3), ("weights", np.array(0.5))):
        one = curvefit.refine(q, **{kw: value})
        full = curvefit.refine(q, **{kw: np.full(len(q), float(value))})
        np.testing.assert_array_equal(one.points, full.points)
        assert one.energy == full.energy
    many = curvefit.refine_many([{"points": q, "radii": 0.1}])
    np.testing.assert_array_equal(many[0].points, curvefit.refine(q, radii=[0.1] * 5).points)


def test_kkt_certificate_of_a_hard_problem():
    """Balls on a noisy star with jittered angles, d = 3, open with clamped ends: the exact
    solver's certificate holds (the package adds nothing to the solver, but this is the path
    users call)."""
    rng = np.random.default_rng(5)
    n = 200
    th = np.sort(2 * np.pi * (np.arange(n) + 0.45 * rng.uniform(-1, 1, n)) / n)
    rad = 1 + 0.5 * (np.arange(n) % 2) + 0.05 * rng.normal(size=n)
    q = np.column_stack([rad * np.cos(th), rad * np.sin(th), 0.2 * rng.normal(size=n)])
    radii = rng.uniform(0, 0.05, n)
    r = curvefit.refine(q, k=4, radii=radii, bc_type=((1, [1, 0, 0]), (1, [0, 1, 0])))
    assert r.kkt_residual <= 1e-9
    # Feasibility as the certificate defines it (crates/refine/src/certify.rs): the violation
    # relative to the length scale L, the largest coordinate distance of a vertex or a data
    # point from the data's centroid — not relative to each radius (a ball of radius 5e-3 may
    # be overshot by 2e-11 = 1.6e-11 L).
    c = q.mean(axis=0)
    length = max(np.abs(r.points - c).max(), np.abs(q - c).max())
    dist = np.linalg.norm(r.points[r.data_vertex] - q, axis=1)
    assert np.max(dist - radii) <= 1e-9 * length
    assert r.active.any()
    same = curvefit.refine(
        q,
        k=4,
        constraint={"type": "balls", "radii": radii},
        boundary={"type": "clamped", "start": [1, 0, 0], "end": [0, 1, 0]},
    )
    assert same.to_dict() == r.to_dict()


@pytest.mark.parametrize("readme", ["README.md", "crates/curvefit-py/README.md"])
def test_readme_example_runs_as_printed(readme, capsys):
    """The five-line example next to the pip line runs and prints what its comment says."""
    text = (Path(__file__).resolve().parents[3] / readme).read_text()
    text = text[text.index("pip install ./crates/curvefit-py"):]
    block = text[text.index("```python\n") + len("```python\n"):]
    block = block[: block.index("```")]
    assert len(block.strip().splitlines()) == 5, block
    exec(compile(block, readme, "exec"), {})
    out = capsys.readouterr().out.split()
    assert out[:2] == ["(96,", "2)"], out
    energy, kkt = float(out[2]), float(out[3])
    assert energy > 0 and kkt <= 1e-9, out

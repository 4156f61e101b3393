"""Every example problem of the repository solved by the package equals the command line's
result, field by field and bit for bit (the binary built from the same tree prints floats in
their shortest round-trip form, so parsing its JSON gives the same doubles)."""

import json
from pathlib import Path

import pytest

import curvefit
from conftest import REPO, cli_result, run_cli

EXAMPLES = sorted(
    list((REPO / "crates" / "curvefit" / "examples" / "data").glob("*.json"))
    + list((REPO / "tests" / "problems").glob("*.json"))
)
SUBCOMMAND = {"refine": "refine", "strip": "strip", "natural": "natural", "surface": "surface"}


def subcommand_of(path: Path):
    return SUBCOMMAND.get(path.name.split("-")[0])


def test_there_are_examples_of_every_json_subcommand():
    found = {subcommand_of(p) for p in EXAMPLES}
    assert {"refine", "strip", "natural", "surface"} <= found, found
    assert len(EXAMPLES) >= 25


@pytest.mark.parametrize("path", [p for p in EXAMPLES if subcommand_of(p)], ids=lambda p: p.name)
def test_example_equals_the_command_line(path):
    sub = subcommand_of(path)
    expected = cli_result(sub, path)
    with open(path) as f:
        problem = json.load(f)
    got = getattr(curvefit, sub)(**problem).to_dict()
    assert list(got) == list(expected), "fields and their order"
    for field in expected:
        assert got[field] == expected[field], field


@pytest.mark.parametrize(
    "stencil,arity,surface,levels",
    [(4, 2, False, 1), (4, 3, True, 2), (6, 2, True, 1), (2, 5, False, 3), (8, 4, False, 2)],
)
def test_scheme_equals_the_command_line(stencil, arity, surface, levels):
    polygon_file = REPO / "tests" / "problems" / "polygon-square.json"
    args = ["scheme", "--stencil", stencil, "--arity", arity, "--apply", polygon_file, "--levels", levels]
    if surface:
        args.append("--surface")
    code, out, err = run_cli(*args)
    assert code == 0, err
    expected = json.loads(out)
    with open(polygon_file) as f:
        polygon = json.load(f)
    got = curvefit.scheme(
        points=stencil, arity=arity, surface=surface, polygon=polygon, levels=levels
    ).to_dict()
    assert got == expected


def test_scheme_without_polygon_equals_the_command_line():
    code, out, err = run_cli("scheme", "--stencil", 6, "--arity", 3)
    assert code == 0, err
    assert curvefit.scheme(6, 3).to_dict() == json.loads(out)


def test_numpy_inputs_equal_the_json_inputs():
    """The examples again, every array of numbers given as a numpy array."""
    import numpy as np

    def number(x):
        return isinstance(x, (int, float)) and not isinstance(x, bool)

    def arrays(v):
        if isinstance(v, dict):
            return {k: arrays(x) for k, x in v.items()}
        if isinstance(v, list) and v and all(number(x) for x in v):
            return np.array(v, dtype=np.float64)
        if isinstance(v, list) and v and all(
            isinstance(x, list) and x and all(number(y) for y in x) for x in v
        ) and len({len(x) for x in v}) == 1:
            return np.array(v, dtype=np.float64)
        if isinstance(v, list):
            return [arrays(x) for x in v]
        return v

    for path in EXAMPLES:
        sub = subcommand_of(path)
        if not sub:
            continue
        with open(path) as f:
            problem = json.load(f)
        plain = getattr(curvefit, sub)(**problem).to_dict()
        numpy_in = getattr(curvefit, sub)(**arrays(problem)).to_dict()
        assert numpy_in == plain, path.name

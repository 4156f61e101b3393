"""Type stubs of the compiled module (crates/curvefit-py/src/lib.rs)."""

from typing import Any, Dict, List, Mapping, Optional, Sequence, Union

__version__: str

def solve(subcommand: str, problem: Mapping[str, Any]) -> Dict[str, Any]:
    """One problem (a mapping of the JSON problem's fields) solved with the GIL released; the
    result's fields as a dict. Raises curvefit.InputError for bad input."""

def solve_many(
    subcommand: str, problems: Sequence[Any], threads: Optional[int] = None
) -> List[Union[Dict[str, Any], BaseException]]:
    """Every problem solved in parallel (rayon) with the GIL released; per problem, in order,
    the result's dict or the curvefit.InputError / curvefit.InternalError instance."""

def schema(subcommand: str) -> str:
    """The JSON Schema of the subcommand's problem, as JSON text."""

def _panic_guard_check() -> None:
    """Raises what a panic inside the library raises (curvefit.InternalError); for the tests."""

"""Shared helpers: the repository, the `curvefit` binary built from the same tree, and running it.

The binary is ``$CURVEFIT_BIN`` or ``target/release/curvefit`` of this repository (built by
``cargo build --release -p curvefit``). Without it the comparisons with the command line are
skipped — except under CI (``CI`` set), where they fail: CI builds it first.
"""

import json
import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]


def binary():
    path = os.environ.get("CURVEFIT_BIN") or str(REPO / "target" / "release" / "curvefit")
    if not os.access(path, os.X_OK):
        msg = f"the curvefit binary is not built ({path}): cargo build --release -p curvefit"
        if os.environ.get("CI"):
            pytest.fail(msg)
        pytest.skip(msg)
    return path


def run_cli(*args, stdin=None):
    """Runs the binary; returns (exit code, stdout, stderr)."""
    p = subprocess.run(
        [binary(), *map(str, args)],
        input=stdin,
        capture_output=True,
        text=True,
        timeout=300,
    )
    return p.returncode, p.stdout, p.stderr


def cli_result(subcommand, problem_file):
    code, out, err = run_cli(subcommand, problem_file)
    assert code == 0, err
    return json.loads(out)


def cli_error(subcommand, problem_text):
    """The command line's one-line error for a problem, without the ``error: `` prefix."""
    code, out, err = run_cli(subcommand, "-", stdin=problem_text)
    assert code == 2, (problem_text, out, err)
    line = err.strip()
    assert line.startswith("error: ") and "\n" not in line, err
    return line[len("error: "):]


@pytest.fixture(scope="session")
def repo():
    return REPO

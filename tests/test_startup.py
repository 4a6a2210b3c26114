"""The command line starts light: `mftyre --help`, `fit --help`, `check FILE`, `eval` of one point import none of
the slow packages they do not need (which modules, not how long: the times are benchmarks/bench_startup.py's)."""
from __future__ import annotations

import json
import subprocess
import sys
import types

import numpy as np

import mftyre
from mftyre.grid_results import format_table

SAMPLE = str(mftyre.files.sample_tir("car_205_60R15_mf61.tir"))
SLOW = ("pandas", "scipy", "lmfit", "matplotlib", "casadi", "fmpy", "pythonfmu", "swift", "fmu")


def _imported_after(code: str) -> dict:
    """Top-level packages in sys.modules after ``code`` ran in a fresh interpreter, per step (``mark(label)``)."""
    script = ("import contextlib, io, json, sys\nseen = {}\n"
              "def mark(label): seen[label] = sorted({m.split('.')[0] for m in sys.modules})\n"
              f"{code}\nprint(json.dumps(seen))")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    return json.loads(done.stdout.splitlines()[-1])


def test_import_mftyre_does_not_import_numpy():
    seen = _imported_after("import mftyre\nmark('import mftyre')")["import mftyre"]
    assert "mftyre" in seen and "numpy" not in seen


def test_cli_commands_import_no_slow_package():
    steps = {"--help": ["--help"], "fit --help": ["fit", "--help"], "check": ["check", SAMPLE],
             "eval": ["eval", SAMPLE]}
    code = "from mftyre.cli import main\n" + "".join(
        f"with contextlib.redirect_stdout(io.StringIO()):\n    assert main({argv!r}) == 0\nmark({label!r})\n"
        for label, argv in steps.items())
    seen = _imported_after(code)
    for label in steps:
        assert not set(SLOW) & set(seen[label]), f"mftyre {label} imported {sorted(set(SLOW) & set(seen[label]))}"


def test_lazy_package_names_are_the_functions():
    """A package name that is also its submodule's name stays the function, as with an eager import."""
    import mftyre.gaps
    import mftyre.gaps.locate  # noqa: F401  (the import system sets the package attribute to the submodule)
    from mftyre.gaps import locate, refit

    assert isinstance(mftyre.gaps.locate, types.FunctionType) and locate is mftyre.gaps.locate
    assert isinstance(refit, types.FunctionType) and "find_gaps" in dir(mftyre.gaps)
    assert mftyre.fit.fit_tir.__module__ == "mftyre.fit.core"


def test_format_table_columns_and_digits():
    values = {"alpha [rad]": np.array([0.0, 0.05]), "fy [N]": np.array([-1234.56789, 3e-7]), "tir": ["a.tir", "b"]}
    lines = format_table(values).splitlines()
    assert lines[0].split() == ["alpha", "[rad]", "fy", "[N]", "tir"]
    assert [line.split() for line in lines[1:]] == [["0", "-1234.57", "a.tir"], ["0.05", "3e-07", "b"]]
    assert len({len(line) for line in lines}) == 1  # right-aligned columns
    import pandas as pd

    assert format_table(pd.DataFrame(values)) == format_table(values)


def test_fit_help_names_every_format_it_reads(capsys):
    from mftyre import cli

    assert cli.main(["fit", "--help"]) == 0
    description = " ".join(capsys.readouterr().out.split())
    assert "to TYDEX (.tdx), TTC (.dat text or .mat) or CSV data" in description

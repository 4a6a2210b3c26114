"""Shared fixtures: where the shared reference material lives, and the sample .tir files."""
from __future__ import annotations

import os
import platform
from pathlib import Path

import pytest

# Native FMUs built by the tests carry the host's binary only (the default would add win64 where MinGW-w64 is
# installed: a second compilation of every FMU, ~30 s of CPU for each SWIFT one); tests/test_fmu_variants.py
# builds the other platforms and checks the default.
if platform.system() == "Linux" and platform.machine() == "x86_64":
    os.environ.setdefault("MFTYRE_FMU_PLATFORMS", "linux64")

PROJECT = Path(__file__).resolve().parents[1]
SHARED = PROJECT.parent / "shared"
MFEVAL_DIR = SHARED / "reference" / "mfeval"
TIR_FILES = PROJECT / "tir_files"


def require_shared(path: Path) -> Path:
    """Skip (with the reason) when the shared reference material is not beside the project."""
    if not path.exists():
        pytest.skip(f"reference material {path} not found: it lives in ../shared beside the project "
                    "(present in CI, absent in a user's clone)")
    return path


@pytest.fixture(scope="session")
def mfeval_dir() -> Path:
    return require_shared(MFEVAL_DIR)


@pytest.fixture(scope="session")
def built_fmu(tmp_path_factory):
    """``built_fmu(tir, *options) -> path``: the FMU of ``mftyre fmu build TIR -o PATH OPTIONS``, built once per
    test process and shared by the FMU test files (pytest-xdist --dist loadfile: one cache per worker). Callers
    read the file, never change it."""
    import argparse

    from mftyre.fmu_command import register

    built = {}

    def build(tir, *options):
        key = (str(tir), *map(str, options))
        if key not in built:
            path = tmp_path_factory.mktemp("built_fmu") / "tyre.fmu"
            parser = argparse.ArgumentParser(prog="mftyre")
            register(parser.add_subparsers(dest="command"))
            ns = parser.parse_args(["fmu", "build", key[0], "-o", str(path), *key[1:]])
            assert ns.func(ns) == 0, key
            built[key] = path
        return built[key]

    return build


#: The sample SWIFT file of the dynamic gap-finder tests (tests/test_gaps_dynamic*.py): it lacks SWIFT_PSTIFF and
#: SWIFT_PDAMP, as the TNO file does.
SWIFT_SAMPLE = TIR_FILES / "car_205_60R15_mf62_swift.tir"
#: Short dynamic runs (s): a lead-in long enough for the noise estimate, the obstacle or step, its decay.
SHORT_RUNS = dict(duration=0.45, lead=0.15)


@pytest.fixture(scope="session")
def sample():
    """The sample SWIFT file as a model (read once per test process; tests derive changed copies, never change it)."""
    import warnings

    import mftyre

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mftyre.load_tir(SWIFT_SAMPLE)


@pytest.fixture(scope="session")
def short_runs(sample):
    """One short cleat run at 30 km/h and one step steer at 40 km/h of the sample file (the reader and command-line
    tests share them: the runs are read, written and searched, never changed)."""
    from mftyre.gaps.dynamic_runs import synthetic_runs

    return synthetic_runs(sample, speeds=(30.0,), steer_speeds=(40.0,), **SHORT_RUNS)


@pytest.fixture(scope="session")
def dynamic_control(sample):
    """(runs, report) of the dynamic gap finder on a control: runs of the sample file itself (nothing to add) at two
    speeds, two pressures away from NOMPRES (where SWIFT_PSTIFF matters) and a step steer."""
    from mftyre.gaps.dynamic import find_dynamic_gaps
    from mftyre.gaps.dynamic_runs import synthetic_runs

    runs = synthetic_runs(sample, speeds=(20.0, 60.0), pressures=(1.9e5, 2.5e5), steer_speeds=(40.0,), seed=1,
                          **SHORT_RUNS)
    return runs, find_dynamic_gaps(runs, sample)

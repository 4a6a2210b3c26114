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

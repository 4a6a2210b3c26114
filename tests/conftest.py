"""Shared fixtures: where the shared reference material lives, and the sample .tir files."""
from __future__ import annotations

from pathlib import Path

import pytest

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

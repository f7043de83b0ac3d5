"""Shared test helpers: where the real meshes are (../shared/data beside the project)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("BRIDGEFIELD_DATA", ROOT.parent / "shared" / "data"))


def data_file(name: str) -> Path:
    """Path of a shared mesh; skips the test when the shared folder is absent."""
    p = DATA / name
    if not p.exists():
        pytest.skip(f"shared data {p} not present")
    return p

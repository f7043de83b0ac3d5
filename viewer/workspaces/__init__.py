"""The explorer's workspaces: self-contained widgets the main window opens."""

from .frep import FrepWorkspace
from .hybrid import HybridWorkspace

__all__ = ["FrepWorkspace", "HybridWorkspace"]

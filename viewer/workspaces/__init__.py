"""The explorer's workspaces: self-contained widgets the main window opens."""

from .hybrid import HybridWorkspace

__all__ = ["HybridWorkspace"]

"""The explorer's workspaces: self-contained widgets the main window opens.

Embed one (``HybridWorkspace(parent)`` / ``FrepWorkspace(parent)`` in a tab or a layout; call its
``shutdown()`` when you drop it) or open one as its own window with :func:`open_workspace`.
"""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QWidget

from .frep import FrepWorkspace
from .hybrid import HybridWorkspace

__all__ = ["FrepWorkspace", "HybridWorkspace", "open_workspace"]

KINDS = {"hybrid": HybridWorkspace, "frep": FrepWorkspace}


def open_workspace(kind: str, parent: QWidget | None = None, *, demo: str | None = None,
                   spec: str | None = None) -> HybridWorkspace | FrepWorkspace:
    """Open the ``"hybrid"`` or ``"frep"`` workspace as a window of its own (owned by parent,
    deleted when closed: closing stops its worker and releases its render window), on a bundled
    demo (default: the first one) or a spec file."""
    cls = KINDS[kind]
    w = cls(parent, demo=None) if spec is not None else (cls(parent) if demo is None else cls(parent, demo=demo))
    w.setWindowFlag(Qt.WindowType.Window, True)
    w.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose, True)
    if spec is not None:
        w.open_spec(spec)
    w.show()
    return w

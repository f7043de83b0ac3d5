"""Closing a QtInteractor so that no wrapper of its GL objects outlives them."""

from __future__ import annotations


def close_plotter(plotter) -> None:
    """``plotter.close()``, then drop the interactor's Python references to its Qt GL context,
    its surface and its fallback context.

    The surface of a QOpenGLWidget is a QOffscreenSurface owned by C++. pyvistaqt keeps a
    wrapper of it (``_surface``) until the interactor itself is collected, and the widget can
    be deleted first. Shiboken's address map then still holds that wrapper, so a Qt call
    returning a new object at the freed address hands back a "QOffscreenSurface" (CI once got
    one from ``QMenu.addAction``). pyvistaqt's ``_forget_context`` drops all three; after
    ``close`` nothing renders any more, so forgetting them is safe. It is looked up with
    getattr: a pyvistaqt without it has nothing to forget.
    """
    plotter.close()
    forget = getattr(plotter, "_forget_context", None)
    if forget is not None:
        forget()

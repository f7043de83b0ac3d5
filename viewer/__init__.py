"""The Bridgefield explorer (PySide6 + pyvistaqt). Importing this package imports no Qt."""

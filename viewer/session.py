"""Sessions: the input paths, the parameters, the camera (and a few view settings) as JSON."""

from __future__ import annotations

import json
from pathlib import Path

from algorithms.params import FieldParams

VERSION = 1


def session_dict(source, params: FieldParams, camera: dict, *, layers: dict | None = None,
                 selection: int = -1, frame: int = 0, darning: str | None = None) -> dict:
    return {
        "bridgefield_session": VERSION,
        "input": None if source is None else {"path": str(Path(source.path).resolve()), "points":
                                              None if source.points is None else str(Path(source.points).resolve()),
                                              "demo": source.demo},
        "params": params.as_dict(),
        "darning": darning,
        "camera": camera,
        "layers": layers or {},
        "selection": int(selection),
        "frame": int(frame),
    }


def save_session(path: str | Path, data: dict) -> None:
    Path(path).write_text(json.dumps(data, indent=1))


def load_session(path: str | Path) -> dict:
    """Read and check a session file; ValueError with the reason when it is not one."""
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: not a session file ({exc})") from None
    if not isinstance(data, dict) or data.get("bridgefield_session") != VERSION:
        raise ValueError(f"{path}: not a Bridgefield session (version {VERSION})")
    data["params"] = FieldParams.from_dict(data.get("params", {}))
    from algorithms.repair import DARNING

    if data.get("darning") is not None and data["darning"] not in DARNING:
        raise ValueError(f"{path}: darning must be one of {', '.join(DARNING)}")
    cam = data.get("camera")
    if cam is not None and not all(k in cam for k in ("position", "focal_point", "view_up")):
        raise ValueError(f"{path}: camera needs position, focal_point and view_up")
    return data

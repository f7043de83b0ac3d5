"""Records of what the algorithms did, step by step, for reports and for the explorer to replay.

A force line is traced once; its record (every step's point, normal, force and tension, and
how it ended) is what the animation, the timeline and the bridge colours read.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

# how a force line ended (spec/repair.md §5)
ARRIVED = "arrived"  # reached a source boundary point: a candidate bridge
TOO_WEAK = "too weak"  # |H n| fell below the threshold
TURNED_BACK = "turned back"  # came back to the base island (or the excluded neighbourhood)
STALLED = "stalled"  # the force reversed against the last direction: an equilibrium
STEP_LIMIT = "step limit"  # max_steps reached
STATUSES = (ARRIVED, TOO_WEAK, TURNED_BACK, STALLED, STEP_LIMIT)


@dataclass(frozen=True)
class BridgeFactors:
    """Every factor of the quality of a straight bridge (eqs. 1-10), for display and debugging."""

    qT: float  # (2) topological compatibility s_A . s_B
    q1: float  # (3) shortness
    q2: float  # (4) effective length through free points (model units)
    q12: float  # (8) q1(q2); equals q1 in light mode
    q3: float  # (5) |sin(n_X, d)|
    q4: float  # (7) continuation of the island's surface at O
    Q: float  # (9) / (10)

    def as_dict(self) -> dict:
        return {k: float(v) for k, v in self.__dict__.items()}


@dataclass(frozen=True, eq=False)
class ForceLine:
    """One traced force line, S steps (the start point included).

    points, normals, forces: (S, 3); tensions: (S,) = |H n| at each point.
    start_vertex / end_vertex: mesh vertex numbers (as in `bridgefield info`); end_* are -1
    unless status == ARRIVED. start_island / end_island: island numbers (-1 when unknown).
    """

    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    forces: NDArray[np.float64]
    tensions: NDArray[np.float64]
    status: str
    start_vertex: int
    start_island: int
    end_vertex: int = -1
    end_island: int = -1

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ValueError(f"unknown force-line status {self.status!r}")

    @property
    def steps(self) -> int:
        return int(len(self.points))

    @property
    def arrived(self) -> bool:
        return self.status == ARRIVED

    @property
    def length(self) -> float:
        if len(self.points) < 2:
            return 0.0
        return float(np.linalg.norm(np.diff(self.points, axis=0), axis=1).sum())

    @property
    def quality(self) -> float:
        """Mean scalar tension along the line, (1/L) * integral of |H n| dl (spec §5)."""
        if len(self.points) < 2:
            return float(self.tensions[0]) if len(self.tensions) else 0.0
        dl = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
        mid = 0.5 * (self.tensions[1:] + self.tensions[:-1])  # trapezoid rule
        total = dl.sum()
        return float((mid * dl).sum() / total) if total > 0 else float(self.tensions.mean())


class Cancelled(Exception):
    """Raised by a long computation when its cancel check returns True."""

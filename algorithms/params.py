"""Parameters of the force-line field and tracing (spec/repair.md §3-6), one frozen dataclass.

Panels build new parameters with ``dataclasses.replace``; invalid values raise a ValueError
that names the parameter.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

MODES = ("light", "full")  # light = M1 (no shielding, no free points), full = M2 (both)
TRACERS = ("simple", "predictor-corrector")
KERNELS = ("gauss", "cauchy")  # q1: exp(-(L/Lc)^2) (default) or the heavy-tailed 1/(1+(L/Lc)^2)
CHARGES = ("length", "unit")


@dataclass(frozen=True)
class FieldParams:
    mode: str = "light"  # "light" (M1) or "full" (M2: shielding (15) + free points (4))
    ki: float = 1.0  # k_i >= 0, factor of interpolation in (9)-(10)
    kt: float = 0.5  # k_t in (0, 1), trust of free-point coordinates: G(0) = k_t / (1 - k_t)
    q1_kernel: str = "gauss"  # shortness index (3)
    lc: float | None = None  # L_c, characteristic value of the discontinuity; None = automatic (§6)
    g_kernel: str = "gauss"  # free-point field G(R) of (4)
    rc_factor: float = 0.25  # R_c = rc_factor * L_c (reach of a free point)
    charge: str = "length"  # h_O: boundary length O stands for, or 1
    step: float | None = None  # tracing step; None = automatic (a fraction of L_c, see step_factor)
    step_factor: float = 0.08  # automatic step = step_factor * L_c
    deviation: float = 0.5  # predictor-corrector search half-width, in steps (d = 0.5 s)
    threshold: float = 0.02  # a line stops as "too weak" when |H n| < threshold * |H n| at its start
    max_steps: int = 2000
    tracer: str = "simple"  # "simple" (2004) or "predictor-corrector" (2010, F4.1)
    shield_stride: int = 32  # full mode: shielding / q2 anchors at most k sources apart along a run, 1 = every source
    # full mode: anchors of the visibility coherence at most this angle apart seen from X (see indicator._coherent_pass)
    coherence_deg: float = 10.0
    # full mode: key points every k-th point of a run of consecutive boundary points; the others take
    # agreeing verdicts of the two key points around them (see indicator._full_point), 1 = off
    point_stride: int = 8

    def __post_init__(self) -> None:
        def bad(name: str, why: str) -> ValueError:
            return ValueError(f"parameter {name}={getattr(self, name)!r}: {why}")

        if self.mode not in MODES:
            raise bad("mode", f"must be one of {', '.join(MODES)}")
        if self.tracer not in TRACERS:
            raise bad("tracer", f"must be one of {', '.join(TRACERS)}")
        if self.q1_kernel not in KERNELS:
            raise bad("q1_kernel", f"must be one of {', '.join(KERNELS)}")
        if self.g_kernel not in KERNELS:
            raise bad("g_kernel", f"must be one of {', '.join(KERNELS)}")
        if self.charge not in CHARGES:
            raise bad("charge", f"must be one of {', '.join(CHARGES)}")
        if not (self.ki >= 0) or self.ki > 1e6:
            raise bad("ki", "must be a number >= 0")
        if not (0 < self.kt < 1):
            raise bad("kt", "must lie strictly between 0 and 1")
        for name in ("lc", "step"):
            v = getattr(self, name)
            if v is not None and not (v > 0 and v < 1e12):
                raise bad(name, "must be a positive number (or None for automatic)")
        for name in ("rc_factor", "step_factor", "deviation"):
            v = getattr(self, name)
            if not (0 < v <= 100):
                raise bad(name, "must be positive")
        if not (0 <= self.threshold < 1):
            raise bad("threshold", "must lie in [0, 1)")
        if not (1 <= self.shield_stride <= 1024) or int(self.shield_stride) != self.shield_stride:
            raise bad("shield_stride", "must be a whole number from 1 to 1024")
        if not (1 <= self.point_stride <= 1024) or int(self.point_stride) != self.point_stride:
            raise bad("point_stride", "must be a whole number from 1 to 1024")
        if not (0 < self.coherence_deg < 90):
            raise bad("coherence_deg", "must lie strictly between 0 and 90 degrees")
        if not (1 <= self.max_steps <= 10_000_000) or int(self.max_steps) != self.max_steps:
            raise bad("max_steps", "must be a whole number >= 1")

    @property
    def shielding(self) -> bool:
        return self.mode == "full"

    @property
    def use_free_points(self) -> bool:
        return self.mode == "full"

    def as_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> FieldParams:
        names = {f.name for f in fields(cls)}
        unknown = set(d) - names
        if unknown:
            raise ValueError(f"unknown parameters: {', '.join(sorted(unknown))}")
        return cls(**d)

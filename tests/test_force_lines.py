"""Force lines (spec/repair.md §5): the spec's numerical checks, recorded steps, both tracers."""

import numpy as np
import pytest

from algorithms.bridges import field_context, trace_from_vertex, trace_in_loop
from algorithms.cases import combine, cut, disk
from algorithms.force_lines import make_targets, trace
from algorithms.mesh import Icadm
from algorithms.params import FieldParams
from algorithms.records import ARRIVED, STALLED, TURNED_BACK

A_BOUNDARY = 193  # disk(segments=64, rings=4): boundary vertex k is 1 + 3 * 64 + k
B_OFFSET = 257  # vertices of one disk


@pytest.fixture(scope="module")
def disks():
    # spec §5: two unit disks in the xy-plane, normals +z, centres 2.6 apart, 64 boundary points
    return Icadm(combine(disk((0, 0, 0)), disk((2.6, 0, 0))))


def arrival_angles(model, params, starts=(0, 4, 7, 10)):
    """Trace from disk A's boundary points (0, 22.5, 39.4, 56.3 degrees); B's arrival angles."""
    ctx = field_context(model, params)
    out = []
    for k in starts:
        ln = trace_from_vertex(model, params, A_BOUNDARY + k, ctx=ctx)
        out.append((ln.end_vertex - B_OFFSET - A_BOUNDARY) * 360 / 64 if ln.arrived else ln.status)
    return out, ln


SPEC_ARRIVALS = [180.0, 168.75, 163.125, 157.5]  # the spec's 180, 169, 163, 158 degrees


@pytest.mark.parametrize("kernel,lc", [("gauss", 0.15), ("gauss", 0.6), ("gauss", 1.0), ("cauchy", 0.6),
                                       ("cauchy", 1.0)])
def test_full_mode_lines_arrive_where_the_spec_says(disks, kernel, lc):
    p = FieldParams(mode="full", q1_kernel=kernel, lc=lc, step=0.05, ki=1.0)
    assert arrival_angles(disks, p)[0] == SPEC_ARRIVALS


@pytest.mark.parametrize("lc", [0.3, 0.6])
def test_light_mode_gaussian_arrives_too(disks, lc):
    p = FieldParams(mode="light", lc=lc, step=0.05)
    assert arrival_angles(disks, p)[0] == SPEC_ARRIVALS


@pytest.mark.parametrize("lc", [0.6, 1.0])
def test_light_mode_heavy_tailed_q1_stalls_before_disk_b(disks, lc):
    p = FieldParams(mode="light", q1_kernel="cauchy", lc=lc, step=0.05)
    ctx = field_context(disks, p)
    for k in (4, 7, 10):  # the oblique lines
        ln = trace_from_vertex(disks, p, A_BOUNDARY + k, ctx=ctx)
        assert ln.status == STALLED
        gap = np.linalg.norm(ln.points[-1, :2] - [2.6, 0]) - 1.0  # distance left to disk B
        assert 0.03 < gap < 0.6  # an equilibrium short of disk B (spec: about 0.2)
        # at the stall the force turns against the line's last direction
        assert ln.forces[-1] @ (ln.points[-1] - ln.points[-2]) < 0


def test_every_step_is_recorded(disks):
    p = FieldParams(lc=0.6, step=0.05)
    ln = trace_from_vertex(disks, p, A_BOUNDARY + 4)
    assert ln.arrived and ln.start_vertex == A_BOUNDARY + 4 and ln.start_island == 0 and ln.end_island == 1
    S = ln.steps
    assert ln.points.shape == ln.normals.shape == ln.forces.shape == (S, 3) and ln.tensions.shape == (S,)
    np.testing.assert_allclose(np.linalg.norm(ln.forces, axis=1), ln.tensions, rtol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(ln.normals, axis=1), 1.0, atol=1e-9)
    seg = np.diff(ln.points, axis=0)
    steps = np.linalg.norm(seg, axis=1)
    np.testing.assert_allclose(steps[:-1], 0.05, rtol=1e-9)  # the last step snaps onto the target
    assert steps[-1] <= 2 * 0.05  # at most a step plus the target's reach
    # (16b) the normal at each point is perpendicular to the step that reached it
    t = seg / steps[:, None]
    assert np.abs((ln.normals[1:-1] * t[:-1]).sum(axis=1)).max() < 1e-9
    np.testing.assert_allclose(ln.points[0], [np.cos(np.pi / 8), np.sin(np.pi / 8), 0], atol=1e-12)
    assert ln.quality > 0 and ln.length == pytest.approx(steps.sum())


class CountingField:
    """Wraps a field and counts its evaluations (the tracers only see the protocol)."""

    def __init__(self, inner):
        self.inner, self.calls = inner, 0
        self.provides = inner.provides

    def sample(self, *a):
        self.calls += 1
        return self.inner.sample(*a)

    def potential(self, *a):
        self.calls += 1
        return self.inner.potential(*a)

    def attraction(self, *a):
        return self.inner.attraction(*a)


def test_predictor_corrector_arrives_and_costs_6_to_8_evaluations_per_step(disks):
    from algorithms.field.indicator import IndicatorField
    from algorithms.field.protocol import Biaf

    counts = {}
    for tracer in ("simple", "predictor-corrector"):
        p = FieldParams(lc=0.6, step=0.05, tracer=tracer)
        ctx = field_context(disks, p)
        other = ctx.sources.group != 0
        sub = ctx.sources.subset(other)
        f = CountingField(Biaf(IndicatorField(sub, p, 0.6)))
        tg = make_targets(sub.points, ctx.edge[other], 0.05, vertex=sub.vertex, island=sub.island)
        fr = ctx.frames[[k for k, fr in enumerate(ctx.frames) if fr.island == 0][0]]
        ln = trace(f, fr.points[0], fr.tangent[0], fr.normal[0], p, tg, step=0.05, avoid=fr.points)
        assert ln.status == ARRIVED and ln.end_vertex == B_OFFSET + A_BOUNDARY + 32
        counts[tracer] = f.calls / ln.steps
    ratio = counts["predictor-corrector"] / counts["simple"]
    assert 5 <= ratio <= 8


def hole_model():
    """A plane (disk of radius 2) with a round hole of radius 1, 64 boundary points on the hole."""
    d = disk((0, 0, 0), 2.0, segments=64, rings=8)
    c = d.vertices[d.faces].mean(axis=1)
    case = cut(d, np.linalg.norm(c[:, :2], axis=1) < 1.0, name="hole", description="round hole")
    return Icadm(case.incomplete)


@pytest.mark.parametrize("lc", [0.5, 1.0])
def test_hole_splitting_line_crosses_to_the_opposite_point(lc):
    m = hole_model()
    from algorithms.boundary import summarize

    frames = summarize(m).loops
    hole = min(frames, key=lambda fr: np.linalg.norm(fr.points, axis=1).mean())
    assert len(hole.vertices) == 64
    start = int(np.argmin(np.linalg.norm(hole.points - [1.0, 0, 0], axis=1)))
    p = FieldParams(lc=lc, step=0.05)
    ln = trace_in_loop(m, hole, start, p, exclude_fraction=12 / 64)
    assert ln.arrived
    np.testing.assert_allclose(m.mesh.vertices[ln.end_vertex], [-1.0, 0, 0], atol=1e-9)


def test_hole_splitting_default_lc_is_the_mean_radius_and_a_line_into_the_window_turns_back():
    m = hole_model()
    from algorithms.boundary import summarize

    hole = min(summarize(m).loops, key=lambda fr: np.linalg.norm(fr.points, axis=1).mean())
    ln = trace_in_loop(m, hole, 0, FieldParams(step=0.05))  # L_c = mean radius = 1
    assert ln.arrived
    # a tiny exclusion window: with L_c = 0.5 the line curls to a near point, which the default
    # window (a fifth of the loop on each side) would have excluded
    ln_small = trace_in_loop(m, hole, 0, FieldParams(lc=0.5, step=0.05), exclude_fraction=4 / 64)
    end = m.mesh.vertices[ln_small.end_vertex] if ln_small.arrived else None
    if end is not None:
        ang = np.degrees(np.arccos(np.clip(end[:2] @ hole.points[0, :2], -1, 1)))
        assert ang < 90  # the spec's 34 or 62 degrees: a sliver
    assert ln_small.status in (ARRIVED, TURNED_BACK, STALLED)  # never across to the far side


def test_trace_in_loop_without_a_model_and_with_a_tiny_window():
    """trace_in_loop works on a bare loop frame (no triangles: light behaviour)."""
    m = hole_model()
    from algorithms.boundary import summarize

    hole = min(summarize(m).loops, key=lambda fr: np.linalg.norm(fr.points, axis=1).mean())
    ln = trace_in_loop(None, hole, 0, FieldParams(step=0.05))
    assert ln.arrived
    np.testing.assert_allclose(m.mesh.vertices[ln.end_vertex], -hole.points[0], atol=1e-9)


class _PythonLoop:
    """The same field behind a plain protocol object: trace then runs its Python loop."""

    def __init__(self, field):
        self.f, self.provides = field, field.provides

    def sample(self, *a):
        return self.f.sample(*a)

    def potential(self, *a):
        return self.f.potential(*a)

    def attraction(self, *a):
        return self.f.attraction(*a)


@pytest.mark.parametrize("mode", ["light", "full"])
@pytest.mark.parametrize("tracer", ["simple", "predictor-corrector"])
@pytest.mark.parametrize("kernel,lc,max_steps", [("gauss", 0.6, 2000), ("cauchy", 1.0, 2000), ("gauss", 0.6, 7)])
def test_fused_tracer_is_the_python_loop(disks, kernel, lc, max_steps, tracer, mode):
    """The numba tracers (field/light_tracer.py) record the same line, status and end as trace's
    Python loop: arrivals, stalls and the step limit."""
    from algorithms.bridges import _trace_unit, _unit_tools
    from algorithms.records import STEP_LIMIT

    p = FieldParams(mode=mode, q1_kernel=kernel, lc=lc, step=0.05, max_steps=max_steps, tracer=tracer)
    ctx = field_context(disks, p)
    li = [k for k, fr in enumerate(ctx.frames) if fr.island == 0][0]
    field, tg, avoid = _unit_tools(ctx, int(ctx.unit[li]), ctx.params)
    fr = ctx.frames[li]
    statuses = set()
    for k in (0, 4, 7, 10):
        args = (fr.points[k], fr.tangent[k], fr.normal[k], ctx.params, tg)
        a = trace(field, *args, step=ctx.step, avoid=avoid)
        b = trace(_PythonLoop(field), *args, step=ctx.step, avoid=avoid)
        assert (a.status, a.end_vertex, len(a.points)) == (b.status, b.end_vertex, len(b.points))
        for u, v in ((a.points, b.points), (a.normals, b.normals), (a.forces, b.forces), (a.tensions, b.tensions)):
            np.testing.assert_allclose(u, v, rtol=1e-9, atol=1e-12)
        statuses.add(a.status)
        assert _trace_unit(ctx, li, k, ctx.params, (field, tg, avoid)).status == a.status
    if mode == "full":  # shielding: the simple tracer's lines all arrive for both kernels (spec §5)
        assert tracer != "simple" or statuses == ({STEP_LIMIT} if max_steps == 7 else {ARRIVED})
        return
    if tracer == "predictor-corrector":  # the same endings as the simple tracer's, not always the same lines
        assert statuses == {STEP_LIMIT} if max_steps == 7 else (ARRIVED if kernel == "gauss" else STALLED) in statuses
        return
    assert statuses == {ARRIVED} if max_steps > 7 and kernel == "gauss" else statuses <= {ARRIVED, STALLED, STEP_LIMIT}
    if max_steps == 7:
        assert statuses == {STEP_LIMIT}
    if kernel == "cauchy":
        assert STALLED in statuses

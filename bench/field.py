"""Benchmark of the indicator field and the force-line tracers (issue 3).

Case: two caps of an ellipsoid (axes 1.4, 1.0, 0.9; a band |z| < 0.12 removed), each cap's
boundary resampled to 2,400 points (the paper's Bunny-1 has 2,424), 300 free points in the band.
Measures, after a warm-up call (numba compiles once and caches):
- the attraction index of one island's 2,400 boundary points against the other's 2,400 sources,
  light mode (M1) and full mode (M2: shielding through the BVH + free points), as point x source
  pairs per second;
- the simple and the predictor-corrector tracers, field steps per second with 2,400 sources.

Run: python -m bench.field   (writes the "field" section of docs/benchmarks.md)
"""

from __future__ import annotations

import os
import time

import numba
import numpy as np

from algorithms.bridges import _trace_unit, _unit_tools, attraction_index, field_context
from algorithms.field.indicator import IndicatorField
from algorithms.mesh import Icadm, Mesh
from algorithms.params import FieldParams

from .report import table, write_section

N_LON = 2400
N_LINES = 24


def caps(n_lon: int = N_LON, rings: int = 10, band: float = 0.12, axes=(1.4, 1.0, 0.9)) -> Icadm:
    """Two ellipsoid caps (z > band and z < -band) as a lat-long mesh, boundary of n_lon points each."""
    verts, faces = [], []
    zs = np.concatenate([np.linspace(band, 1.0, rings + 1), np.linspace(-band, -1.0, rings + 1)])
    ang = 2 * np.pi * np.arange(n_lon) / n_lon
    off = 0
    for cap in range(2):
        z = zs[cap * (rings + 1):(cap + 1) * (rings + 1)]
        ring_ids = []
        for zz in z[:-1]:
            r = np.sqrt(max(1 - zz * zz, 0))
            verts.append(np.stack([r * np.cos(ang), r * np.sin(ang), np.full(n_lon, zz)], 1))
            ring_ids.append(off + np.arange(n_lon))
            off += n_lon
        verts.append(np.array([[0.0, 0.0, z[-1]]]))
        pole = off
        off += 1
        for k in range(rings - 1):
            a, b = ring_ids[k], ring_ids[k + 1]
            a1, b1 = np.roll(a, -1), np.roll(b, -1)
            f1, f2 = np.stack([a, a1, b1], 1), np.stack([a, b1, b], 1)
            faces += [f1, f2] if cap == 0 else [f1[:, ::-1], f2[:, ::-1]]
        last = ring_ids[-1]
        fp = np.stack([last, np.roll(last, -1), np.full(n_lon, pole)], 1)
        faces.append(fp if cap == 0 else fp[:, ::-1])
    v = np.vstack(verts) * np.asarray(axes)
    rng = np.random.default_rng(0)
    t = rng.uniform(0, 2 * np.pi, 300)
    zz = rng.uniform(-band, band, 300)
    rr = np.sqrt(1 - zz * zz)
    free = np.stack([rr * np.cos(t), rr * np.sin(t), zz], 1) * np.asarray(axes)
    return Icadm(Mesh(v, np.vstack(faces)), free_points=free, source="two ellipsoid caps")


def best_of(fn, repeat: int = 3, *, cpu: bool = False) -> float:
    """Best of repeat runs: wall time, or (cpu=True, for one thread) the process's CPU time, which
    other processes on the shared machine disturb less."""
    clock = time.process_time if cpu else time.perf_counter
    ts = []
    for _ in range(repeat):
        t = clock()
        fn()
        ts.append(clock() - t)
    return min(ts)


def _load() -> str:
    return ", ".join(f"{v:.1f}" for v in os.getloadavg())


def main() -> None:
    load_before = _load()
    model = caps()
    rows_field, rows_trace = [], []
    results = {}
    bare = Icadm(model.mesh, source=model.source)  # the same case without free points
    threads = numba.get_num_threads()
    exact = FieldParams(mode="full", shield_stride=1, point_stride=1)
    cases = {}
    for mode, mdl in (("light", model), ("full", model), ("full, no free points", bare)):
        p = FieldParams(mode=mode.split(",")[0])
        ctx = field_context(mdl, p)
        S = ctx.sources
        base = S.group == 0
        pts = S.subset(base)
        src = S.subset(~base)
        field = IndicatorField(src, p, ctx.lc, bvh=ctx.bvh, free=ctx.free)
        # the points in loop order, with their loop and position (as attraction_index passes them)
        args = dict(x_vertex=pts.vertex, x_loop=pts.loop, x_pos=pts.pos)
        field.evaluate(pts.points[:64], x_vertex=pts.vertex[:64])  # warm-up (JIT cache load, threads)
        field.evaluate(pts.points, **args)
        cases[mode] = (p, ctx, pts, src, field, args)
    for nt in (1, threads):  # CPU time of one thread, then wall time with all threads
        numba.set_num_threads(nt)
        for _ in range(5):  # the modes in turn, so that a change of load hits them alike
            for mode, case in cases.items():
                pts, field, args = case[2], case[4], case[5]
                t = best_of(lambda: field.evaluate(pts.points, **args), 1, cpu=nt == 1)
                results.setdefault(mode, {}).setdefault(nt, []).append(t)
    for mode, (p, ctx, pts, src, field, args) in cases.items():
        t_kernel = {nt: min(v) for nt, v in results[mode].items()}
        results[mode] = t_kernel
        ev = field.evaluate(pts.points, **args)
        t_omega = best_of(lambda: attraction_index(ctx))
        nominal = len(pts) * len(src)
        err = ""
        if mode != "light":
            ref = IndicatorField(src, exact, ctx.lc, bvh=ctx.bvh, free=ctx.free)
            t0 = time.perf_counter()
            H_ref = ref.evaluate(pts.points, **args).H
            t_exact = time.perf_counter() - t0
            err = f"{np.abs(ev.H - H_ref).max() / np.abs(H_ref).max():.1e}"
        rows_field.append([mode, len(pts), len(src), f"{t_kernel[1] * 1e3:.1f}", f"{t_kernel[threads] * 1e3:.1f}",
                           f"{nominal / t_kernel[threads] / 1e6:.1f}", ev.pairs if mode != "light" else nominal,
                           f"{t_omega * 1e3:.1f}", err])
        if mode != "light":
            rows_field.append([f"{mode}, exact (every pair tested)", len(pts), len(src), "",
                               f"{t_exact * 1e3:.0f}", f"{nominal / t_exact / 1e6:.1f}", ev.pairs, "", "0"])
        li = [k for k, fr in enumerate(ctx.frames) if fr.island == 0][0]
        starts = np.arange(0, N_LON, N_LON // N_LINES)
        for tracer in ("simple", "predictor-corrector"):
            pt = FieldParams(mode=p.mode, tracer=tracer, lc=ctx.lc, step=ctx.step)
            tools = _unit_tools(ctx, int(ctx.unit[li]), pt)
            _trace_unit(ctx, li, int(starts[0]), pt, tools)  # warm-up
            dt = np.inf
            for _ in range(3):  # CPU time: the lines run on one thread
                t = time.process_time()
                lines = [_trace_unit(ctx, li, int(i), pt, tools) for i in starts]
                dt = min(dt, time.process_time() - t)
            steps = sum(ln.steps for ln in lines)
            arrived = sum(ln.arrived for ln in lines)
            rows_trace.append([mode, tracer, len(lines), arrived, steps, f"{dt:.3f}", f"{steps / dt:.0f}"])
    spd = {(r[0], r[1]): float(r[6]) for r in rows_trace}
    modes = ("light", "full", "full, no free points")
    pc_ratio = {m: spd[(m, "simple")] / spd[(m, "predictor-corrector")] for m in modes}
    r1 = {m: results[m][1] / results["light"][1] for m in ("full", "full, no free points")}
    rn = {m: results[m][threads] / results["light"][threads] for m in ("full", "full, no free points")}
    load_after = _load()
    body = f"""## Indicator field and force lines (`python -m bench.field`)

Case: {model.source}, {model.mesh.n_faces} faces, two islands with {N_LON} boundary points each
(the paper's Bunny-1 has 2,424), {len(model.free_points)} free points in the gap; automatic L_c
and step. The attraction index of island 0's boundary against island 1's {N_LON} sources:

{table(["mode", "points", "sources", "1 thread, CPU ms", f"{threads} threads, wall ms",
        f"M pairs/s ({threads} threads)", "pairs after pruning", "Omega of all 4800 points incl. normals, ms",
        "max rel. error of H vs exact"], rows_field)}

Full mode costs {r1['full']:.1f}x light mode with the free points, {r1['full, no free points']:.1f}x without
them on one thread (CPU time, best of 5), {rn['full']:.1f}x and {rn['full, no free points']:.1f}x with
{threads} threads (wall time, best of 5; the modes timed in turn); target: at most 5x. Both modes run the same points in
parallel over the points (numba prange), so the two ratios compare like with like. Load average:
{load_before} before, {load_after} after, on {os.cpu_count()} cores (the machine is shared with other
agents: wall times vary by up to 2x between runs, the one-thread CPU times much less).

What full mode does per point (algorithms/field/indicator.py, parameters in FieldParams): a pair
is a candidate when its Gaussian weight is above exp(-16) of the nearest source's (free points may
rescue a pair by the factor 1 + G(0)). Pairs are then decided with visibility coherence, three
approximations, each a parameter (stride 1 and point_stride 1 decide every pair exactly: the
"exact" rows, whose H the last column compares with):
- along the sources (`shield_stride` = 32, `coherence_deg` = 10): on each run of consecutive
  sources, anchors at most 32 sources and 10 degrees apart seen from the point are decided
  exactly; between two anchors that agree the verdict is shared; where they disagree the middle
  source is decided and both halves are treated alike (bisection). A near source, whose
  neighbours subtend more than 10 degrees, is always decided exactly;
- q2 (4) is computed at the anchors (a lattice of the free points' sum G, 16 samples, trilinear)
  and q2/L interpolated in between; the pruning limit is applied to the interpolated q2, so the
  anchors on both sides of it cost one more q2 each, not a re-test of every source in between;
- across points (`point_stride` = 8): along each run of consecutive boundary points (x_loop /
  x_pos given, as attraction_index does), every 8th point is a key point decided as above; a
  point between two key points takes a source's verdict (negligible, visible or shielded) and
  q2/L (interpolated) from them when both agree and they subtend at most 10 degrees at the
  source (and the point lies near their chord: no sharp corner between them); only the other
  pairs (the edges of the candidate range, where the keys disagree) are decided for the point.
In this case no segment is shielded (a chord between the two rims stays inside the ellipsoid),
so the coherence is exact without free points; the shielded and partly shielded cases are
tested against every-pair shielding in tests/test_field_shielding.py (a partial wall, two caps).
What remains is mostly the candidate loops themselves (the pairs within the free-point pruning
radius, about 1,300 per point here against light mode's 570) and about 1 us per BVH segment test
at the key points.

Force lines from {N_LINES} evenly spaced boundary points of island 0 (each step evaluates the field
of {N_LON} sources at one point, single-threaded; CPU time, best of 3; the time includes each line's set-up):

{table(["mode", "tracer", "lines", "arrived", "steps", "time, s", "steps/s"], rows_trace)}

Predictor-corrector / simple cost per step: light {pc_ratio['light']:.1f}x, full {pc_ratio['full']:.1f}x,
full without free points {pc_ratio['full, no free points']:.1f}x (2010 §6.4 reports 6-8x; ours evaluates the
field 6 times per step: the predictor's normal, 4 extra potentials across it, the corrected point,
against the simple tracer's one). Both tracers run their steps fused in numba in both modes
(field/light_tracer.py: field, normal (16b), predictor-corrector search, target and turned-back
tests without returning to Python; the same lines as the Python loop, tests/test_force_lines.py).
A step's target and turned-back tests (brute force over the 2,400 targets and avoid points, about
the cost of one light-mode field evaluation) are common to both tracers, hence less than 6x in
light mode; in full mode one field evaluation at a point of the gap costs about 0.1 ms
(shielding and q2 for one point, without the coherence across points).

For scale, the paper's Table 1 (a 500 MHz Pentium III, whole repair including darning):

| model | class | N_bnd | N_bdg | M1 time, s | M1 artifacts | M2 time, s |
|---|---|---|---|---|---|---|
| Bunny-1 | ICM2 | 2424 | 749 | 11 | no | 30 |
| Bunny-2 | ICM2 | 2319 | 3615 | 16 | yes | 66 |
| Woman-1 | ICM2 | 1526 | 7938 | 34 | no | 283 |
| Bunny-3 | ICM3 | 3272 | 4150 | 48 | yes | 185 |
"""
    print(body)
    write_section("field", body)


if __name__ == "__main__":
    main()

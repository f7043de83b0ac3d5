"""`bridgefield warmup` (algorithms/warmup.py): after it, real repairs compile no kernel.

A fresh install compiles the numba kernels on first use (about a minute); setup runs the warm-up
so that the first `bridgefield repair` does not. The check runs in a fresh interpreter (kernels
compiled by other tests in this process would hide a gap): it warms up, notes every kernel's
compiled signatures, repairs shapes the warm-up never saw (the closed bunny cut by a band into
islands with free points, the bunny with 60 holes, its ear tips among them: thin parts, bad
angles; the fandisk with a hole across its crease), and
asserts that no kernel needed a new signature (one would be compiled on a user's first run).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

from conftest import ROOT, data_file

SCRIPT = r"""
import json, sys
import numpy as np
from algorithms.warmup import kernels, warm
from algorithms.cases import cut, face_centroids
from algorithms.io import load_raw
from algorithms.mesh import Mesh
from algorithms.normalize import normalize
from algorithms.params import FieldParams
from algorithms.repair import RepairParams, repair

out = warm()
before = {n: {str(s) for s in d.signatures} for n, d in kernels()}
bunny = Mesh(*load_raw(sys.argv[1]))
c = face_centroids(bunny)
d = bunny.bbox_diagonal()
band = np.abs(c[:, 1] - bunny.vertices[:, 1].mean()) < 0.0125 * d
rng = np.random.default_rng(7)
holes = np.zeros(len(c), dtype=bool)
for vi in rng.choice(len(bunny.vertices), 60, replace=False):  # bench.cases' bunny-many-holes
    holes |= np.linalg.norm(c - bunny.vertices[vi], axis=1) < 0.03 * d
fan = Mesh(*load_raw(sys.argv[2]))
fc = face_centroids(fan)
ball = np.linalg.norm(fc - fan.vertices[np.argmax(fan.vertices[:, 2])], axis=1) < 0.1 * fan.bbox_diagonal()
cases = [cut(bunny, band, name="band", description="", free_points=100, seed=1),
         cut(bunny, holes, name="holes", description=""),
         cut(fan, ball, name="ball", description="")]
for case in cases:
    for mode in ("light", "full"):
        m = normalize(case.incomplete.vertices, case.incomplete.faces, extra_points=case.free_points)
        repair(m, RepairParams(field=FieldParams(mode=mode)))
after = {n: {str(s) for s in d.signatures} for n, d in kernels()}
new = {n: sorted(after[n] - before.get(n, set())) for n in after if after[n] - before.get(n, set())}
used = sorted(n for n, d in kernels() if d.signatures)
print(json.dumps({"new": new, "kernels": out["kernels"], "used": used}))
"""


def test_after_warmup_real_repairs_compile_nothing():
    bunny, fandisk = data_file("bunny_closed.ply"), data_file("fandisk.obj")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    r = subprocess.run([sys.executable, "-c", SCRIPT, str(bunny), str(fandisk)], capture_output=True, text=True,
                       cwd=ROOT, env=env, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    got = json.loads(r.stdout.strip().splitlines()[-1])
    assert got["kernels"] >= 40  # the field, tracer and darning kernels are all found
    assert got["new"] == {}, f"kernels compiled after the warm-up: {got['new']}"
    # the shapes reach the kernels the demos do not: the RBF of thin parts, the angle smoothing
    for k in ("algorithms.darning.fair_kernels.dense_solve", "algorithms.darning.refine_kernels._smooth_rounds"):
        assert k in got["used"]


def test_warmup_command_reports_the_kernels():
    from algorithms.cli import build_parser, run_command

    args = build_parser().parse_args(["warmup", "--quiet"])
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert run_command(args) == 0
    line = buf.getvalue().strip().splitlines()[-1]
    assert line.startswith("warmup: ") and "kernels ready" in line
    assert int(line.split()[1]) >= 40

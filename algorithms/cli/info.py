"""`bridgefield info FILE`: what an incomplete model is made of."""

from __future__ import annotations

import argparse

import numpy as np

from ..boundary import summarize
from ..normalize import set_aside_summary
from .common import add_input, dumps, load_input_model

NAME = "info"
HELP = "islands, boundary loops, free points, Euler/genus, class guess and what normalisation set aside"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_input(p)
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.add_argument("--all-set-aside", action="store_true", help="list every set-aside face in the text report")


def report(model) -> dict:
    s = summarize(model)
    d = s.as_dict()
    d["source"] = model.source
    d["faces"] = model.mesh.n_faces
    d["free_points"] = model.free_point_counts()
    d["flipped_faces"] = int(model.flipped.sum())
    d["split_vertices"] = int((np.arange(len(model.vertex_origin)) != model.vertex_origin).sum())
    d["set_aside"] = {"count": len(model.set_aside), "by_reason": set_aside_summary(model),
                      "faces": [{"face": x.face, "vertices": list(x.vertices), "reason": x.reason}
                                for x in model.set_aside]}
    return d


def run(args: argparse.Namespace) -> int:
    model = load_input_model(args)
    d = report(model)
    if args.json:
        print(dumps(d))
        return 0
    fp = d["free_points"]
    print(f"{d['source']}: {d['faces']} faces kept, class guess {d['class']}")
    print(f"free points: {fp['total']} ({fp['unreferenced']} unreferenced in the file, "
          f"{fp['from_set_aside_faces']} from set-aside faces, {fp['point_cloud']} from the point cloud)")
    for isl in d["islands"]:
        print(f"island {isl['index']}: {isl['faces']} faces, {isl['vertices']} vertices, "
              f"{len(isl['loops'])} loops, Euler {isl['euler']}, genus {isl['genus']:g}")
    for lp in d["loops"]:
        print(f"  loop {lp['index']} (island {lp['island']}): {lp['vertices']} vertices, "
              f"length {lp['length']:.4g}, starts at vertex {lp['start_vertex']}")
    sa = d["set_aside"]
    if sa["count"]:
        reasons = ", ".join(f"{n} {k}" for k, n in sa["by_reason"].items())
        print(f"set aside: {sa['count']} faces ({reasons})")
        shown = sa["faces"] if args.all_set_aside else sa["faces"][:10]
        for x in shown:
            print(f"  face {x['face']} {tuple(x['vertices'])}: {x['reason']}")
        if len(shown) < sa["count"]:
            print(f"  ... {sa['count'] - len(shown)} more (--all-set-aside or --json to list them)")
    if d["flipped_faces"]:
        print(f"flipped: {d['flipped_faces']} faces re-wound to agree with their island")
    if d["split_vertices"]:
        print(f"split: {d['split_vertices']} vertex copies where separate surface sheets meet")
    return 0

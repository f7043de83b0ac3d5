"""`bridgefield warmup`: compile the numba kernels into their on-disk cache (setup runs it)."""

from __future__ import annotations

import argparse

NAME = "warmup"
HELP = "compile the field and darning kernels ahead of the first repair (.ci/setup runs it; ~1 min once)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quiet", action="store_true", help="print only the summary line")


def run(args: argparse.Namespace) -> int:
    from ..warmup import warm

    out = warm(None if args.quiet else (lambda label: print(f"warmup: {label}", flush=True)))
    n = len(out["compiled"])  # functions compiled now (kernels and the helpers they call)
    how = f"{n} functions compiled now and cached for the next run" if n else "all loaded from the cache"
    print(f"warmup: {out['kernels']} kernels ready in {out['seconds']:.1f} s ({how})")
    return 0

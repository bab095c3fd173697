"""Measures the Python layer's overhead on an identification: the wall time of
`indentify.identify(...)` seen from Python against the pipeline's own wall time inside the
study layer (`Result.wall_seconds`, timed by `indentify_study::identify::run`), and the
optimizer's time (`Result.seconds`).

    python python/examples/overhead.py [CONFIG] [--repeat 10] [--set path=value ...]

Defaults: examples/r1-maxwell.ron (R1: Maxwell, 20 x 20 mesh, 90 steps), 10 repeats after
one warm-up run; prints the medians and the per-call overhead.
"""

import argparse
import statistics
import sys
import time

import indentify


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("config", nargs="?", default="examples/r1-maxwell.ron")
    ap.add_argument("--repeat", type=int, default=10)
    ap.add_argument("--set", action="append", default=[], dest="sets")
    ap.add_argument("--progress", action="store_true", help="with a (no-op) progress callback")
    args = ap.parse_args()
    progress = (lambda rec: None) if args.progress else None
    indentify.identify(args.config, sets=args.sets, progress=progress)  # warm-up
    calls, walls, optim = [], [], []
    for _ in range(args.repeat):
        start = time.perf_counter()
        r = indentify.identify(args.config, sets=args.sets, progress=progress)
        calls.append(time.perf_counter() - start)
        walls.append(r.wall_seconds)
        optim.append(r.seconds)
    call, wall, opt = (statistics.median(x) for x in (calls, walls, optim))
    over = [c - w for c, w in zip(calls, walls)]
    print(f"{args.config}: {r.iterations} iterations, {len(r.history)} progress records, "
          f"{len(r.fit['t'])} curve points")
    print(f"median over {args.repeat} runs: Python call {call * 1e3:.2f} ms, "
          f"study pipeline (wall_seconds) {wall * 1e3:.2f} ms, optimizer (seconds) {opt * 1e3:.2f} ms")
    print(f"overhead of the Python layer: median {statistics.median(over) * 1e6:.0f} us, "
          f"max {max(over) * 1e6:.0f} us per call ({statistics.median(over) / wall * 100:.3f}% of the run)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

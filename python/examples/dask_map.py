"""Identifies a synthetic two-phase Maxwell map with Dask: one `indentify.identify` per
indent on a `dask.distributed.LocalCluster`, then prints the recovered phase of each indent
as a map and how many match the truth.

    python python/examples/dask_map.py [--n 4] [--workers 2] [--full] [--dir DIR]

Needs `dask[distributed]` (`pip install "dask[distributed]"`); without it the script says
so and exits with status 0. By default the map is coarse (an 8 x 8 mesh, 10 steps per
segment): 16 indents take a few seconds on 2 cores.
"""

import argparse
import math
import sys
import tempfile
import time

import indentify


def identify_indent(base: str, data: str) -> dict:
    """One indent: the base configuration fitted to the indent's record (runs on a worker;
    the call releases the GIL, so threaded workers run in parallel too)."""
    r = indentify.identify(base, data=data)
    return {"E": r.params["E"], "eta": r.params["eta"], "converged": r.converged, "seconds": r.wall_seconds}


def nearest_phase(E: float, eta: float, phases: dict) -> str:
    """The phase whose (E, eta) is nearest in log space."""
    def dist(p):
        return math.hypot(math.log(E / p["E"]), math.log(eta / p["eta"]))

    return min(phases, key=lambda name: dist(phases[name]))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=4, help="indents per side (default 4)")
    ap.add_argument("--workers", type=int, default=2, help="Dask worker processes (default 2)")
    ap.add_argument("--noise", type=float, default=0.02, help="noise amplitude (default 0.02)")
    ap.add_argument("--full", action="store_true", help="R1's full mesh instead of the coarse one")
    ap.add_argument("--dir", help="where to write the map (default: a temporary folder)")
    args = ap.parse_args()
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        print("dask_map.py: skipped: dask.distributed is not installed "
              "(pip install \"dask[distributed]\")")
        return 0

    with tempfile.TemporaryDirectory() as tmp:
        folder = args.dir or tmp
        m = indentify.make_map(folder, n=args.n, noise=args.noise, coarse=not args.full)
        print(f"map: {len(m['indents'])} indents in {folder} (base {m['base']})")
        start = time.perf_counter()
        with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True) as cluster, \
                Client(cluster) as client:
            futures = [client.submit(identify_indent, m["base"], i["data"], key=f"identify-{i['id']}")
                       for i in m["indents"]]
            results = client.gather(futures)
        wall = time.perf_counter() - start
        right = 0
        rows: dict[float, list[str]] = {}
        for indent, r in zip(m["indents"], results):
            phase = nearest_phase(r["E"], r["eta"], m["phases"])
            right += phase == indent["phase"]
            rows.setdefault(indent["y"], []).append(phase if r["converged"] else phase.lower())
            print(f"{indent['id']}: E = {r['E']:9.1f} MPa, eta = {r['eta']:9.1f} MPa s -> phase {phase}"
                  f" (truth {indent['phase']}){'' if r['converged'] else ' (not converged)'}")
        print("recovered phases (rows by y):")
        for y in sorted(rows):
            print("  " + " ".join(rows[y]))
        cpu = sum(r["seconds"] for r in results)
        print(f"{right}/{len(results)} phases recovered; {wall:.1f} s wall for {cpu:.1f} s of "
              f"identifications on {args.workers} workers")
        return 0 if right == len(results) else 1


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""One dense garment to a few bodies through refit-batch's own path (refit.batch.run on a
Dask LocalCluster of one worker process, as `refit-batch` runs it), with or without the
worker keeping freed memory (refit.keep_freed_memory, which the workers call).

Dask starts its worker processes with MALLOC_TRIM_THRESHOLD_=65536 (its config
`distributed.nanny.pre-spawn-environ`), so without the call glibc hands back every
freed block at once and each body faults its memory in again.

    /usr/bin/python3 bench/batch_dense.py GARMENT BODY_A FEATURES BODY_B... [--no-keep] [--threads 2]

Prints one line: the variant, the batch's wall seconds, then per body its resize and
(first body) bind milliseconds. Outputs go to a temporary folder and are removed.
Run the two variants taking turns (bench/README.md, "The Python module keeps freed
memory").
"""
import argparse
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "release", "python"))
import distributed  # noqa: E402

from refit import batch  # noqa: E402


class NoKeep(distributed.WorkerPlugin):
    """Makes the worker's refit.keep_freed_memory() do nothing."""

    def setup(self, worker):
        import refit

        refit.keep_freed_memory = lambda: True


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("garment")
    ap.add_argument("body_a")
    ap.add_argument("features")
    ap.add_argument("bodies", nargs="+")
    ap.add_argument("--no-keep", action="store_true", help="the workers do not keep freed memory")
    ap.add_argument("--threads", type=int, default=2, help="engine threads per body")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as out:
        manifest = os.path.join(out, "bodies.csv")
        with open(manifest, "w") as f:
            for k, body in enumerate(a.bodies):
                f.write("%s,%s\n" % (os.path.abspath(body), os.path.join(out, "out_%d.obj" % k)))
        job = batch.Job(garment=os.path.abspath(a.garment), body_a=os.path.abspath(a.body_a),
                        features=os.path.abspath(a.features), threads=a.threads)
        rows = batch.read_manifest(manifest)
        with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster, distributed.Client(cluster) as client:
            if a.no_keep:
                client.register_worker_plugin(NoKeep())
            start = time.perf_counter()
            summary = batch.run(job, rows, client)
            wall = time.perf_counter() - start
    line = ["plain" if a.no_keep else "keep", "wall %.2f" % wall]
    for e in summary["bodies"]:
        t = e.get("timings_ms", {})
        line.append("%s resize %.0f%s" % (e["name"], t.get("resize", float("nan")),
                                          " bind %.0f" % t["bind"] if "bind" in t else ""))
    print(" ".join(line))


if __name__ == "__main__":
    main()

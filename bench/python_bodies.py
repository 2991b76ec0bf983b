#!/usr/bin/env python3
"""One garment to several bodies from Python, with or without keeping freed memory
(refit.keep_freed_memory; docs/python.md), in one of two ways:

- `--via module` (default): one Python process binds with refit.Binding and resizes
  each body, as a host program does; it calls refit.keep_freed_memory() first unless
  `--plain`.
- `--via batch`: refit.batch.run on a Dask LocalCluster of one worker process, as
  `refit-batch` runs it (outputs to a temporary folder, removed). The workers call
  refit.keep_freed_memory(); `--plain` makes that call do nothing (a worker plugin).
  Dask starts its worker processes with MALLOC_TRIM_THRESHOLD_=65536 (its config
  `distributed.nanny.pre-spawn-environ`): glibc then hands back every freed block.

    /usr/bin/python3 bench/python_bodies.py GARMENT BODY_A FEATURES BODY_B... [--via module|batch] [--plain]

Prints one line: keep or plain, the seconds of the binding (module) or of the whole
batch, then each body's. Run the two variants taking turns (bench/README.md, "The
Python module keeps freed memory").
"""
import argparse
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "release", "python"))
import refit  # noqa: E402


def stem(path):
    return os.path.splitext(os.path.basename(path))[0]


def in_this_process(a):
    if not a.plain and not refit.keep_freed_memory():
        sys.exit("python_bodies: keep_freed_memory does nothing here (not glibc's allocator)")
    start = time.perf_counter()
    garment = refit.read_garment(a.garment, keep_text=False)
    binding = refit.Binding(garment, refit.read_body(a.body_a), features=refit.read_features(a.features),
                            threads=a.threads)
    line = ["bind %.2f" % (time.perf_counter() - start)]
    for path in a.bodies:
        t = time.perf_counter()
        binding.resize(refit.read_body(path))
        line.append("%s %.2f" % (stem(path), time.perf_counter() - t))
    return line


def on_a_worker(a):
    import distributed

    from refit import batch

    class NoKeep(distributed.WorkerPlugin):
        def setup(self, worker):
            import refit as worker_refit

            worker_refit.keep_freed_memory = lambda: True

    with tempfile.TemporaryDirectory() as out:
        manifest = os.path.join(out, "bodies.csv")
        with open(manifest, "w") as f:
            for k, body in enumerate(a.bodies):
                f.write("%s,%s\n" % (os.path.abspath(body), os.path.join(out, "out_%d.obj" % k)))
        job = batch.Job(garment=os.path.abspath(a.garment), body_a=os.path.abspath(a.body_a),
                        features=os.path.abspath(a.features), threads=a.threads)
        with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster, distributed.Client(cluster) as client:
            if a.plain:
                client.register_worker_plugin(NoKeep())
            start = time.perf_counter()
            summary = batch.run(job, batch.read_manifest(manifest), client)
            line = ["batch %.2f" % (time.perf_counter() - start)]
    for e, path in zip(summary["bodies"], a.bodies):
        t = e.get("timings_ms", {})
        line.append("%s %.2f%s" % (stem(path), t.get("resize", float("nan")) / 1000.0,
                                   " (bind %.2f)" % (t["bind"] / 1000.0) if "bind" in t else ""))
    return line


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("garment")
    ap.add_argument("body_a")
    ap.add_argument("features")
    ap.add_argument("bodies", nargs="+")
    ap.add_argument("--via", choices=["module", "batch"], default="module")
    ap.add_argument("--plain", action="store_true", help="without keeping freed memory")
    ap.add_argument("--threads", type=int, default=2, help="engine threads per body")
    a = ap.parse_args()
    line = in_this_process(a) if a.via == "module" else on_a_worker(a)
    print(" ".join(["plain" if a.plain else "keep"] + line))


if __name__ == "__main__":
    main()

"""Dask batch throughput (issue 15): the shared dress (with its features) resized to
200 bodies made by morphing the shared bodies (A_female plus random blends of the
three female targets' differences, generated here, not stored), on a LocalCluster of 1
and of 2 worker processes (one core each), taking turns; every output is compared
byte for byte with `refit resize --to-list` on the same manifest.

    /usr/bin/python3 bench/batch_throughput.py --build build/release [--bodies 200] [--rounds 2]

Throughput = bodies / wall time of refit.batch.run (binding included, cluster start-up
not); prints each run, the medians and the ratio 2 workers / 1 worker."""
import argparse
import logging
import os
import statistics
import subprocess
import sys
import tempfile

import numpy as np


def read_obj(path):
    v, f = [], []
    for line in open(path):
        if line.startswith("v "):
            v.append([float(t) for t in line.split()[1:4]])
        elif line.startswith("f "):
            f.append(line)
    return np.array(v), f


def make_bodies(data, folder, count, seed=15):
    """A + sum_i w_i (T_i - A): weights uniform in [-0.5, 1] per target, scaled to a sum of at most 1."""
    a, faces = read_obj(os.path.join(data, "bodies", "A_female.obj"))
    targets = [read_obj(os.path.join(data, "bodies", n + ".obj"))[0] - a for n in ("F_heavier", "F_thinner", "F_taller")]
    rng = np.random.default_rng(seed)
    paths = []
    for k in range(count):
        w = rng.uniform(-0.5, 1.0, len(targets))
        w /= max(1.0, np.abs(w).sum())
        v = a + sum(wi * t for wi, t in zip(w, targets))
        path = os.path.join(folder, "body%03d.obj" % k)
        with open(path, "w") as out:
            out.write("".join("v %.6f %.6f %.6f\n" % tuple(p) for p in v))
            out.write("".join(faces))
        paths.append(path)
    return paths


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--build", default="build/release")
    p.add_argument("--data", default=os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data"))
    p.add_argument("--bodies", type=int, default=200)
    p.add_argument("--rounds", type=int, default=2)
    a = p.parse_args()
    sys.path.insert(0, os.path.join(os.path.abspath(a.build), "python"))
    os.environ["PYTHONPATH"] = os.path.join(os.path.abspath(a.build), "python")  # for the workers
    import distributed
    from refit import batch

    cli = os.path.join(a.build, "tools", "refit")
    garment = os.path.abspath(os.path.join(a.data, "garments", "dress_on_A_female.obj"))
    body_a = os.path.abspath(os.path.join(a.data, "bodies", "A_female.obj"))
    features = os.path.abspath(os.path.join(os.path.dirname(__file__), "quality", "features", "dress.json"))
    job = batch.Job(garment=garment, body_a=body_a, features=features)
    with tempfile.TemporaryDirectory() as d:
        bodies = make_bodies(a.data, d, a.bodies)

        def manifest(name):
            path = os.path.join(d, name + ".csv")
            with open(path, "w") as f:
                f.write("".join("%s,%s/%s\n" % (b, name, os.path.basename(b)) for b in bodies))
            return path

        ref = subprocess.run([cli, "resize", "--quiet", "--garment", garment, "--from", body_a, "--features", features,
                              "--to-list", manifest("cli")], capture_output=True, text=True)
        assert ref.returncode == 0, ref.stderr
        rates = {1: [], 2: []}
        for k in range(a.rounds):
            for workers in (1, 2):
                name = "w%d_r%d" % (workers, k)
                rows = batch.read_manifest(manifest(name))
                cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                                   dashboard_address=None, silence_logs=logging.ERROR)
                client = distributed.Client(cluster)
                try:
                    s = batch.run(job, rows, client)
                finally:
                    client.close()
                    cluster.close()
                assert s["counts"]["done"] == len(rows), s["counts"]
                same = sum(open(r.output, "rb").read() == open(os.path.join(d, "cli", os.path.basename(r.output)),
                                                                "rb").read() for r in rows)
                rates[workers].append(s["bodies_per_s"])
                print("round %d, %d worker(s): %d bodies in %.1f s, %.2f bodies/s; %d/%d outputs identical to "
                      "refit resize" % (k, workers, len(rows), s["wall_s"], s["bodies_per_s"], same, len(rows)),
                      flush=True)
                assert same == len(rows)
    m1, m2 = statistics.median(rates[1]), statistics.median(rates[2])
    print("\nmedian throughput: 1 worker %.2f bodies/s, 2 workers %.2f bodies/s: %.2fx" % (m1, m2, m2 / m1))


if __name__ == "__main__":
    main()

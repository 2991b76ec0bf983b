#!/usr/bin/env python3
"""One garment to several bodies in one Python process, through the module `refit`,
as a host program or a batch worker runs it (docs/python.md): the time of the binding
and of each body's resize, with or without refit.keep_freed_memory().

    /usr/bin/python3 bench/python_bodies.py GARMENT BODY_A FEATURES BODY_B... [--keep] [--threads 2]

Prints one line: keep or plain, the binding's seconds, then each body's. Run the two
variants taking turns (bench/README.md, "The Python module keeps freed memory").
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "release", "python"))
import refit  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("garment")
    ap.add_argument("body_a")
    ap.add_argument("features")
    ap.add_argument("bodies", nargs="+")
    ap.add_argument("--keep", action="store_true", help="call refit.keep_freed_memory() first")
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    if a.keep and not refit.keep_freed_memory():
        sys.exit("python_bodies: keep_freed_memory does nothing here (not glibc's allocator)")
    start = time.perf_counter()
    garment = refit.read_garment(a.garment, keep_text=False)
    binding = refit.Binding(garment, refit.read_body(a.body_a), features=refit.read_features(a.features),
                            threads=a.threads)
    line = ["keep" if a.keep else "plain", "bind %.2f" % (time.perf_counter() - start)]
    for path in a.bodies:
        t = time.perf_counter()
        binding.resize(refit.read_body(path))
        line.append("%s %.2f" % (os.path.splitext(os.path.basename(path))[0], time.perf_counter() - t))
    print(" ".join(line))


if __name__ == "__main__":
    main()

"""The shared MakeHuman garments densified by ../shared/data/make_dense.py, made once
per output path and kept (the benchmarks on real dense garments share them)."""
import os
import subprocess
import sys


def densified(data, garment_file, out, min_vertices, quiet=True):
    """Path `out`, made from ../shared/data/garments/<garment_file> with at least
    min_vertices vertices unless it already exists."""
    if not os.path.exists(out):
        subprocess.run([sys.executable, os.path.join(data, "make_dense.py"), os.path.join(data, "garments", garment_file),
                        out, "--min-vertices", str(min_vertices)], check=True,
                       stdout=subprocess.DEVNULL if quiet else None)
    return out

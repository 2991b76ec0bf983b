"""The Blender add-on, headless: installs it in a fresh Blender (its own user folders),
runs its operator on the shared dress and jeans, and compares the new objects with
`refit resize` on the same files. Exit 77 (CTest's skip) where Blender or the shared
data is absent."""
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

blender = shutil.which("blender")
if not blender:
    print("blender test skipped: no `blender` on this machine (tools/setup.sh installs Debian's)")
    sys.exit(77)
data = os.environ.get("REFIT_SHARED_DATA", "")
if not data or not os.path.isdir(os.path.join(data, "garments")):
    print("blender test skipped: ../shared/data is absent")
    sys.exit(77)
cli = os.environ["REFIT_CLI"]
here = os.path.dirname(os.path.abspath(__file__))
root = os.path.join(here, "..", "..")


def float32_exact(src, dst):
    """The file with every v coordinate rounded to float32, which is what Blender
    stores: then Blender and the command line start from the same numbers."""
    with open(src) as f, open(dst, "w") as out:
        for line in f:
            if line.startswith("v "):
                xyz = np.float32([float(t) for t in line.split()[1:4]])
                line = "v %s %s %s\n" % tuple(repr(float(c)) for c in xyz)
            out.write(line)


with tempfile.TemporaryDirectory() as d:
    for name, src in (("A_female", "bodies/A_female.obj"), ("F_heavier", "bodies/F_heavier.obj"),
                      ("dress", "garments/dress_on_A_female.obj"), ("jeans", "garments/jeans_on_A_female.obj")):
        float32_exact(os.path.join(data, src), os.path.join(d, name + ".obj"))
    features = os.path.join(root, "bench", "quality", "features", "dress.json")
    for garment, extra in (("dress", ["--features", features]), ("jeans", [])):
        subprocess.run([cli, "resize", "--quiet", "--garment", os.path.join(d, garment + ".obj"), "--from",
                        os.path.join(d, "A_female.obj"), "--to", os.path.join(d, "F_heavier.obj"), "--out",
                        os.path.join(d, "cli_" + garment + ".obj")] + extra, check=True)
    env = dict(os.environ, BLENDER_USER_SCRIPTS=os.path.join(d, "scripts"),
               BLENDER_USER_CONFIG=os.path.join(d, "config"))
    run = subprocess.run([blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python",
                          os.path.join(here, "blender_test.py"), "--", d,
                          os.path.join(root, "tools", "blender", "refit_blender.py"), features],
                         env=env, capture_output=True, text=True)
    print(run.stdout[-4000:], run.stderr[-4000:])
    sys.exit(run.returncode)

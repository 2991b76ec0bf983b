"""Python overhead (issue 15): binding the 1M procedural dress and applying the
binding to one body, from Python (the module refit) and from C++ (bind_apply_cpu),
in process CPU time with 1 engine thread, the two taking turns process by process.

    /usr/bin/python3 bench/python_overhead.py --build build/release [--rounds 3] [--repeats 2]

Prints every run, then the medians and the ratios Python / C++: of all runs, of the
first in each process (which also pays the process's first page faults) and of the later ones."""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

import numpy as np

PY = r"""
import json, sys, time
import refit
g = refit.read_garment(sys.argv[1]); a = refit.read_body(sys.argv[2]); b = refit.read_body(sys.argv[3])
f = refit.read_features(sys.argv[4])
bind, apply = [], []
for _ in range(int(sys.argv[5])):
    t = time.process_time(); binding = refit.Binding(g, a, features=f, threads=int(sys.argv[6]))
    bind.append(time.process_time() - t)
    t = time.process_time(); r = binding.resize(b)
    apply.append(time.process_time() - t)
print(json.dumps({"bind_s": bind, "apply_s": apply}))
"""


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--build", default="build/release")
    p.add_argument("--vertices", type=int, default=1000000)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--repeats", type=int, default=2, help="bind + apply per process")
    p.add_argument("--threads", type=int, default=1)
    a = p.parse_args()
    cli = os.path.join(a.build, "tools", "refit")
    cpp = os.path.join(a.build, "bench", "bind_apply_cpu")
    env = dict(os.environ, PYTHONPATH=os.path.join(os.path.abspath(a.build), "python"))
    with tempfile.TemporaryDirectory() as d:
        files = [os.path.join(d, n) for n in ("dress.obj", "A.obj", "B.obj", "features.json")]
        subprocess.run([cli, "generate", "--vertices", str(a.vertices), "--garment-out", files[0], "--body-out",
                        files[1], "--features-out", files[3]], check=True, capture_output=True)
        subprocess.run([cli, "generate", "--hip", "104", "--belly", "6", "--body-out", files[2]], check=True,
                       capture_output=True)
        args = files + [str(a.repeats), str(a.threads)]
        times = {"cpp": {"bind_s": [], "apply_s": []}, "python": {"bind_s": [], "apply_s": []}}
        for k in range(a.rounds):
            for who, cmd in (("cpp", [cpp] + args), ("python", [sys.executable, "-c", PY] + args)):
                out = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True, env=env).stdout)
                for key in out:
                    times[who][key] += out[key]
                print("round %d %-6s bind %s apply %s" % (k, who, ["%.3f" % x for x in out["bind_s"]],
                                                          ["%.3f" % x for x in out["apply_s"]]))
    # The first bind and apply of a process also pay its first page faults: apart.
    for label, pick in (("all", slice(None)), ("first of each process", slice(0, None, a.repeats)),
                        ("later in the process", [i for i in range(a.rounds * a.repeats) if i % a.repeats])):
        print("\nmedians, %s (CPU s, %d thread(s)):" % (label, a.threads))
        for key in ("bind_s", "apply_s"):
            c = statistics.median(np.array(times["cpp"][key])[pick])
            py = statistics.median(np.array(times["python"][key])[pick])
            print("  %-6s C++ %.3f  Python %.3f  Python / C++ %.3f" % (key[:-2], c, py, py / c))

if __name__ == "__main__":
    main()

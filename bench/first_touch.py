#!/usr/bin/env python3
"""What this machine charges for memory a process touches for the first time.

    /usr/bin/python3 bench/first_touch.py [--mb 800] [--repeat 4] [--pause 10] [--pages 4k|huge]

Maps --mb of anonymous memory (--pages huge: huge pages advised, as glibc's malloc
does under REFIT_HUGE_PAGES=1; 4k: huge pages advised against, as refit runs by default),
writes one byte per 4 KiB page and reports the time, first right after another
such run (the pages the last one freed are still backed by the host) and then
after --pause seconds (a virtual machine that reports free pages to its host,
such as this one, has given them back by then). Medians of --repeat.
bench/README.md ("Memory first touch") has the figures and what they mean for
refit's own timings.
"""
import argparse
import mmap
import statistics
import subprocess
import sys
import time


def touch(mb, pages):
    n = mb << 20
    start = time.perf_counter()
    m = mmap.mmap(-1, n, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)  # as malloc's memory
    advice = "MADV_HUGEPAGE" if pages == "huge" else "MADV_NOHUGEPAGE"
    if hasattr(mmap, advice):
        m.madvise(getattr(mmap, advice))
    for i in range(0, n, 4096):
        m[i] = 1
    return time.perf_counter() - start


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mb", type=int, default=800)
    ap.add_argument("--repeat", type=int, default=4)
    ap.add_argument("--pause", type=float, default=10.0)
    ap.add_argument("--pages", choices=("4k", "huge"), default="4k")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(touch(args.mb, args.pages))
        return 0
    # Each touch in a process of its own: a process's freed memory is reused by the
    # process itself, never touched fresh again.
    child = lambda: float(subprocess.run([sys.executable, __file__, "--child", "--mb", str(args.mb), "--pages", args.pages],
                                         capture_output=True, text=True, check=True).stdout)
    paused, back = [], []
    for _ in range(args.repeat):
        time.sleep(args.pause)
        paused.append(child())
        back.append(child())
    for name, t in (("after a pause", paused), ("back to back", back)):
        m = statistics.median(t)
        print("%s pages, %s: %d MB in %.3f s (median of %d), %.2f ms per MB" % (args.pages, name, args.mb, m, len(t),
                                                                                1000 * m / args.mb))
    return 0


if __name__ == "__main__":
    sys.exit(main())

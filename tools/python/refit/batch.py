"""Batch grading on Dask: one garment (with its features) resized to every body of a
manifest, on any Dask cluster or a local one (the `refit-batch` command).

Each worker process binds the garment once (on its first body) and applies the binding
to every body it is given; each output is written atomically (a temporary file renamed
over it), so an output that exists is complete, and a re-run skips it (resume after a
crash). A body that fails is reported and the others go on; a worker that dies has its
bodies run again elsewhere. At the end a summary (per body: status, timings, key
metrics) is written as JSON.

The manifest is the CSV of `refit resize --to-list` (docs/cli.md): body file, output
file, optional name per row; read by the same rules as tools/refit/manifest.cpp.
"""
import argparse
import csv
import dataclasses
import glob
import json
import logging
import os
import re
import socket
import sys
import threading
import time
import uuid

import refit

# Exit codes of the command line (docs/cli-errors.md).
EXIT_OK, EXIT_INPUT, EXIT_USAGE, EXIT_RESOURCES, EXIT_SOME_FAILED = 0, 1, 2, 3, 4


@dataclasses.dataclass(frozen=True)
class Job:
    """What every body shares: the garment, body A, the features and the options of
    refit.Binding. Paths are absolute (workers may run elsewhere)."""

    garment: str
    body_a: str
    features: str = ""
    units: str = "cm"
    stage: str = "full"
    symmetry: str = "auto"
    collision: bool = True
    clearance: float = 0.2
    follow_body: float = 0.0  # refit resize --follow-body (cm; 0: off)
    threads: int = 1  # engine threads per body: one Dask task slot is one core
    metrics: bool = False
    redo: bool = False  # resize bodies whose output exists too


@dataclasses.dataclass(frozen=True)
class Row:
    """One body of the manifest."""

    index: int  # position in the manifest (0-based, header and comments not counted)
    body: str
    output: str
    name: str
    line: int


def read_manifest(path):
    """The manifest's rows: fields trimmed, blank rows and rows whose first field starts
    with '#' skipped, a first row 'body,output[,name]' taken as a header, relative paths
    resolved against the manifest's folder, the name defaulting to the body file's stem.
    refit.InputError naming the file and line for anything else."""
    folder = os.path.dirname(os.path.abspath(path))
    try:
        with open(path, newline="") as f:
            text = f.read()
    except OSError as e:
        raise refit.InputError("%s: cannot open the manifest: %s" % (path, e.strerror)) from None
    reader = csv.reader(text.splitlines(keepends=True), skipinitialspace=True)  # a quote after spaces quotes, as libcsv
    rows, outputs = [], set()
    for fields in reader:
        fields = [x.strip() for x in fields]
        line = reader.line_num
        if not fields or fields == [""] or fields[0].startswith("#"):
            continue
        if not rows and len(fields) >= 2 and fields[0].lower() == "body" and fields[1].lower() == "output":
            continue
        if not 2 <= len(fields) <= 3:
            raise refit.InputError("%s:%d: expected body,output[,name], found %d fields" % (path, line, len(fields)))
        if not fields[0] or not fields[1]:
            raise refit.InputError("%s:%d: empty body or output file name" % (path, line))
        body, output = (os.path.normpath(os.path.join(folder, p)) for p in fields[:2])
        name = fields[2] if len(fields) == 3 and fields[2] else os.path.splitext(os.path.basename(fields[0]))[0]
        if output in outputs:
            raise refit.InputError("%s:%d: output %s appears twice" % (path, line, fields[1]))
        outputs.add(output)
        rows.append(Row(len(rows), body, output, name, line))
    if not rows:
        raise refit.InputError("%s: the manifest lists no bodies" % path)
    return rows


def shard_rows(rows, index, count):
    """The index-th of count contiguous slices (as `refit resize --shard I/N`)."""
    return rows[index * len(rows) // count:(index + 1) * len(rows) // count]


# --- on the workers ------------------------------------------------------------------

_bindings = {}  # Job -> (Binding, Garment), one per worker process and job
_bind_lock = threading.Lock()


def _bound(job):
    """This process's binding of the job, made on first use; with the time it took
    (None when it was already there)."""
    with _bind_lock:
        if job in _bindings:
            return _bindings[job] + (None,)
        start = time.perf_counter()
        # A worker resizes body after body: freed buffers are kept for the next
        # one, overriding the MALLOC_TRIM_THRESHOLD_ Dask starts workers with (the
        # 1M dress: about half the time per body; docs/python.md).
        refit.keep_freed_memory()
        garment = refit.read_garment(job.garment, keep_text=False)  # write_garment reads the file again
        features = refit.read_features(job.features, units=job.units) if job.features else None
        binding = refit.Binding(garment, refit.read_body(job.body_a), features=features, units=job.units,
                                stage=job.stage, symmetry=job.symmetry, collision=job.collision,
                                clearance=job.clearance, threads=job.threads, metrics=job.metrics,
                                follow_body=job.follow_body)
        _bindings[job] = (binding, garment)
        return binding, garment, (time.perf_counter() - start) * 1000.0


def key_metrics(report):
    """The few numbers of a resize report worth a summary line (docs/cli.md)."""
    features = report.get("features", [])
    m = {
        "feature_shape_error": {c["name"]: c.get("shape_error_output") for c in features},
        "feature_shape_error_max": max((c.get("shape_error_output", 0.0) for c in features), default=None),
        "feature_gap": report.get("surface", {}).get("feature_gap"),
        "inside_after": report.get("collision", {}).get("inside_after"),
    }
    if "metrics" in report:
        m["penetration"] = report["metrics"]["result"]["penetration"]["fraction"]
    return m


def resize_body(job, row):
    """Resizes the garment to one body and writes its output (a Dask task). Never
    raises for bad input: the entry says what failed."""
    start = time.perf_counter()
    entry = {"index": row.index, "name": row.name, "body": row.body, "output": row.output,
             "worker": "%s:%d" % (socket.gethostname(), os.getpid())}
    if not job.redo and os.path.exists(row.output):
        # Already written (by an earlier run, or by a worker that died after writing it).
        return dict(entry, status="skipped")
    try:
        binding, garment, bind_ms = _bound(job)
    except refit.Error as e:
        return dict(entry, status="bind_failed", error=str(e), exit_code=e.exit_code)
    timings = {} if bind_ms is None else {"bind": bind_ms}
    try:
        t = time.perf_counter()
        body = refit.read_body(row.body)
        timings["read"] = (time.perf_counter() - t) * 1000.0
        t = time.perf_counter()
        r = binding.resize(body)
        timings["resize"] = (time.perf_counter() - t) * 1000.0
        t = time.perf_counter()
        refit.write_garment(garment, r.positions, row.output)
        timings["write"] = (time.perf_counter() - t) * 1000.0
    except refit.Error as e:
        return dict(entry, status="failed", error=str(e), exit_code=e.exit_code)
    timings["total"] = (time.perf_counter() - start) * 1000.0
    return dict(entry, status="done", timings_ms=timings, metrics=key_metrics(r.report), warnings=r.warnings)


# --- on the client -------------------------------------------------------------------


def _write_json_atomically(path, doc):
    tmp = os.path.join(os.path.dirname(os.path.abspath(path)), ".%s.tmp%d" % (os.path.basename(path), os.getpid()))
    with open(tmp, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
    os.replace(tmp, path)


def _remove_stale_temporaries(rows):
    """Temporaries a killed worker left beside the outputs (.NAME.PID.N.tmp, the
    engine's atomic writes): nobody writes them any more once every body is accounted for."""
    removed = 0
    for row in rows:
        folder, name = os.path.split(row.output)
        for tmp in glob.glob(os.path.join(glob.escape(folder), "." + glob.escape(name) + ".*.tmp")):
            if re.fullmatch(r"\.%s\.\d+\.\d+\.tmp" % re.escape(name), os.path.basename(tmp)):
                os.remove(tmp)
                removed += 1
    return removed


def _earlier_entries(summary_path):
    try:
        with open(summary_path) as f:
            return {e["output"]: e for e in json.load(f).get("bodies", []) if e.get("status") == "done"}
    except (OSError, ValueError, KeyError, TypeError):
        return {}


def run(job, rows, client, summary_path=None, on_progress=None):
    """Resizes job's garment to every row's body on the Dask `client`; returns the
    summary (also written to summary_path). on_progress(done, total, entry) is called
    as each body is accounted for. refit.Error when the binding itself fails (every
    body would fail the same way)."""
    from distributed import as_completed
    from distributed.scheduler import KilledWorker

    started = time.time()
    clock = time.perf_counter()
    earlier = _earlier_entries(summary_path) if summary_path else {}
    entries, todo = {}, []
    for row in rows:
        if not job.redo and os.path.exists(row.output):
            before = earlier.get(row.output, {})
            entries[row.index] = dict(before, index=row.index, name=row.name, body=row.body, output=row.output,
                                      status="skipped")
        else:
            os.makedirs(os.path.dirname(row.output) or ".", exist_ok=True)
            todo.append(row)
    total, done = len(rows), 0
    for row in rows:
        if row.index in entries:
            done += 1
            if on_progress:
                on_progress(done, total, entries[row.index])
    run_id = uuid.uuid4().hex[:8]
    futures = {client.submit(resize_body, job, row, key="refit-%s-%d" % (run_id, row.index), pure=False): row
               for row in todo}
    for future in as_completed(futures):
        row = futures[future]
        try:
            entry = future.result()
        except KilledWorker as e:
            entry = {"index": row.index, "name": row.name, "body": row.body, "output": row.output,
                     "status": "failed", "error": "every worker that ran it died (%s)" % e}
        except Exception as e:  # an internal error of one body: report it, go on
            entry = {"index": row.index, "name": row.name, "body": row.body, "output": row.output,
                     "status": "failed", "error": "internal error: %s: %s" % (type(e).__name__, e)}
        if entry["status"] == "bind_failed":
            client.cancel(list(futures))
            error = {1: refit.InputError, 2: refit.UsageError, 3: refit.ResourceError}.get(entry["exit_code"],
                                                                                          refit.Error)
            raise error(entry["error"])
        entries[row.index] = entry
        done += 1
        if on_progress:
            on_progress(done, total, entry)
    wall = time.perf_counter() - clock
    bodies = [entries[row.index] for row in rows]
    counts = {s: sum(1 for e in bodies if e["status"] == s) for s in ("done", "skipped", "failed")}
    summary = {
        "version": refit.__version__,
        "job": dataclasses.asdict(job),
        "started": time.strftime("%Y-%m-%dT%H:%M:%S", time.localtime(started)),
        "wall_s": wall,
        "workers": len(client.scheduler_info().get("workers", {})),
        "counts": counts,
        "bodies_per_s": counts["done"] / wall if wall > 0 else None,
        "temporaries_removed": _remove_stale_temporaries(rows),
        "bodies": bodies,
    }
    if summary_path:
        _write_json_atomically(summary_path, summary)
    return summary


class _ProgressLine:
    """bodies done / total on stderr: rewritten in place on a terminal, a line at
    most every second (and the last) otherwise."""

    def __init__(self, quiet):
        self.quiet, self.tty, self.last, self.failed = quiet, sys.stderr.isatty(), 0.0, 0

    def __call__(self, done, total, entry):
        if entry["status"] == "failed":
            self.failed += 1
            print("refit-batch: error: %s (body %s skipped)" % (entry["error"], entry["name"]), file=sys.stderr)
        if self.quiet:
            return
        now = time.monotonic()
        if done < total and not self.tty and now - self.last < 1.0:
            return
        self.last = now
        text = "refit-batch: %d/%d bodies done (%d failed)" % (done, total, self.failed)
        print(("\r" + text) if self.tty else text, end="\n" if not self.tty or done == total else "",
              file=sys.stderr, flush=True)


def _parser():
    p = argparse.ArgumentParser(
        prog="refit-batch",
        description="Resize one garment to every body of a manifest on a Dask cluster (a local one by default).",
        epilog="Exit codes: 0 ok, 1 bad input, 2 usage, 3 out of resources, 4 some bodies failed.")
    p.add_argument("--garment", required=True, help="garment OBJ around body A")
    p.add_argument("--from", dest="body_a", required=True, help="body A")
    p.add_argument("--manifest", required=True, help="CSV: body file, output file, optional name per row")
    p.add_argument("--features", default="", help="feature curves (JSON)")
    p.add_argument("--summary", help="summary JSON (default: MANIFEST's name + .summary.json beside it)")
    p.add_argument("--shard", help="only the I-th of N slices of the manifest (I from 0)")
    p.add_argument("--scheduler", help="address of a running Dask scheduler (else a local cluster)")
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="local cluster: worker processes")
    p.add_argument("--threads", type=int, default=1, help="engine threads per body (default 1: a worker is a core)")
    p.add_argument("--units", default="cm", choices=["cm", "mm", "m", "in"])
    p.add_argument("--stage", default="full", choices=["warp", "features", "full"])
    p.add_argument("--symmetry", default="auto", choices=["auto", "x", "none"])
    p.add_argument("--no-collision", action="store_true")
    p.add_argument("--clearance", type=float, default=0.2, help="collision clearance in cm (0 to 10)")
    p.add_argument("--follow-body", type=float, default=0.0,
                   help="feature samples that sat within this of body A (cm) follow body B (0 to 10; 0: off)")
    p.add_argument("--metrics", action="store_true", help="add the metrics of the result to each body's report")
    p.add_argument("--redo", action="store_true", help="resize bodies whose output exists too")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    return p


def main(argv=None):
    p = _parser()
    a = p.parse_args(argv)
    shard = None
    if a.shard:
        m = re.fullmatch(r"(\d+)/(\d+)", a.shard)
        if not m or not int(m.group(1)) < int(m.group(2)):
            p.error("--shard: '%s' is not I/N with 0 <= I < N" % a.shard)
        shard = int(m.group(1)), int(m.group(2))
    if a.workers < 1 or not 0 <= a.threads <= 1024:
        p.error("--workers must be at least 1 and --threads within 0 to 1024")
    if not 0 <= a.clearance <= 10:
        p.error("--clearance: %s is outside 0 to 10 cm" % a.clearance)
    if not 0 <= a.follow_body <= 10:
        p.error("--follow-body: %s is outside 0 to 10 cm" % a.follow_body)
    job = Job(garment=os.path.abspath(a.garment), body_a=os.path.abspath(a.body_a),
              features=os.path.abspath(a.features) if a.features else "", units=a.units, stage=a.stage,
              symmetry=a.symmetry, collision=not a.no_collision, clearance=a.clearance, follow_body=a.follow_body,
              threads=a.threads,
              metrics=a.metrics, redo=a.redo)
    summary_path = a.summary or os.path.splitext(a.manifest)[0] + ".summary.json"
    try:
        rows = read_manifest(a.manifest)
        if shard:
            rows = shard_rows(rows, *shard)
        for path in (job.garment, job.body_a) + ((job.features,) if job.features else ()):
            if not os.path.isfile(path):
                raise refit.InputError("%s: no such file" % path)
        from distributed import Client, LocalCluster

        if a.scheduler:
            client, cluster = Client(a.scheduler), None
        else:
            cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.ERROR)
            client = Client(cluster)
        try:
            summary = run(job, rows, client, summary_path, _ProgressLine(a.quiet))
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    except refit.Error as e:
        print("refit-batch: error: %s" % e, file=sys.stderr)
        return e.exit_code
    c = summary["counts"]
    if not a.quiet:
        print("refit-batch: %d written, %d already done, %d failed in %.1f s; summary %s"
              % (c["done"], c["skipped"], c["failed"], summary["wall_s"], summary_path), file=sys.stderr)
    return EXIT_SOME_FAILED if c["failed"] else EXIT_OK


if __name__ == "__main__":
    sys.exit(main())

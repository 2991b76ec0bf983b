"""refit-batch on a real Dask LocalCluster of two worker processes: a bad body is
reported and the others go on, a worker killed mid-run does not lose or duplicate a
body, outputs equal the command line's, a re-run resumes; and the manifest is read
as `refit resize --to-list` reads it."""
import json
import logging
import os
import signal
import subprocess
import sys

import pytest

import refit

distributed = pytest.importorskip("distributed", reason="python3-distributed is not installed")
from heap_probe import large_block_mapped_alone  # noqa: E402
from refit import batch  # noqa: E402

CLI = os.environ.get("REFIT_CLI", "refit")
GOOD = 6


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    """Body A, a 3000-vertex dress with features, GOOD bodies B and one bad one; a
    manifest (absolute paths, so messages match the command line's) and the command
    line's outputs for it."""
    d = tmp_path_factory.mktemp("batch")
    subprocess.run([CLI, "generate", "--vertices", "3000", "--body-out", str(d / "A.obj"), "--garment-out",
                    str(d / "dress.obj"), "--features-out", str(d / "features.json")], check=True, capture_output=True)
    rows = []
    for i in range(GOOD):
        body = d / ("B%d.obj" % i)
        subprocess.run([CLI, "generate", "--hip", str(92 + 3 * i), "--belly", str(i), "--body-out", str(body)],
                       check=True, capture_output=True)
        rows.append(body)
    (d / "bad.obj").write_text("v 0 0 0\nv 1 0 0\nf 1 2 3\n")
    rows.insert(2, d / "bad.obj")

    def manifest(name, out):
        lines = ["body,output,name"] + ["%s,%s" % (b, d / out / (b.stem + ".obj")) for b in rows]
        (d / name).write_text("\n".join(lines) + "\n")
        return d / name

    ref = subprocess.run([CLI, "resize", "--quiet", "--garment", str(d / "dress.obj"), "--from", str(d / "A.obj"),
                          "--features", str(d / "features.json"), "--to-list", str(manifest("ref.csv", "ref"))],
                         capture_output=True, text=True)
    assert ref.returncode == 4, ref.stderr  # the bad body failed, the others were written
    cli_error = [line for line in ref.stderr.splitlines() if line.startswith("refit: error: ")][0]
    return {"dir": d, "manifest": manifest, "cli_error": cli_error,
            "job": batch.Job(garment=str(d / "dress.obj"), body_a=str(d / "A.obj"), features=str(d / "features.json"))}


def outputs_of(folder):
    return sorted(os.listdir(folder)) if os.path.isdir(folder) else []


def check_outputs_equal_the_command_lines(d, out):
    assert outputs_of(d / out) == sorted("B%d.obj" % i for i in range(GOOD))  # no temporaries, no bad.obj
    for i in range(GOOD):
        name = "B%d.obj" % i
        assert (d / out / name).read_bytes() == (d / "ref" / name).read_bytes(), name


def test_bad_body_and_a_worker_killed_mid_run(case):
    d = case["dir"]
    rows = batch.read_manifest(str(case["manifest"]("kill.csv", "kill")))
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                       silence_logs=logging.CRITICAL)
    client = distributed.Client(cluster)
    killed = []

    def kill_a_busy_worker(done, total, entry):
        if killed or entry["status"] != "done":
            return
        busy = [w for w, keys in client.processing().items() if keys]
        if busy:
            pid = client.run(os.getpid, workers=busy[:1])[busy[0]]
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

    try:
        summary = batch.run(case["job"], rows, client, str(d / "kill.summary.json"), kill_a_busy_worker)
    finally:
        client.close()
        cluster.close()
    assert killed, "no worker was busy after the first body"
    assert [e["index"] for e in summary["bodies"]] == list(range(GOOD + 1))  # each body once, in manifest order
    bad = summary["bodies"][2]
    assert bad["status"] == "failed" and bad["exit_code"] == 1
    assert case["cli_error"] == "refit: error: %s (body skipped)" % bad["error"]
    good = [e for e in summary["bodies"] if e is not bad]
    # A body the killed worker had written before it died is found done ("skipped") by its retry.
    assert all(e["status"] in ("done", "skipped") for e in good)
    assert summary["counts"]["failed"] == 1
    assert json.loads((d / "kill.summary.json").read_text())["counts"] == summary["counts"]
    check_outputs_equal_the_command_lines(d, "kill")
    done = [e for e in good if e["status"] == "done"]
    assert {"read", "resize", "write", "total"} <= set(done[0]["timings_ms"])
    assert done[0]["metrics"]["inside_after"] == 0 and done[0]["metrics"]["feature_shape_error_max"] is not None
    assert sum("bind" in e["timings_ms"] for e in done) <= 3  # each worker process binds once (3: one restarted)


def test_workers_keep_freed_memory(case, tmp_path):
    # Dask starts its workers with MALLOC_TRIM_THRESHOLD_=65536: without the workers'
    # refit.keep_freed_memory() each body of a dense garment faulted its memory in
    # again (bench/README.md, "The Python module keeps freed memory").
    row = "%s,%s\n" % (case["dir"] / "B0.obj", tmp_path / "B0.obj")
    (tmp_path / "one.csv").write_text(row)
    cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None,
                                       silence_logs=logging.CRITICAL)
    client = distributed.Client(cluster)
    try:
        fresh = list(client.run(large_block_mapped_alone, 30 << 20).values())
        summary = batch.run(case["job"], batch.read_manifest(str(tmp_path / "one.csv")), client)
        after = list(client.run(large_block_mapped_alone, 30 << 20).values())
    finally:
        client.close()
        cluster.close()
    assert summary["counts"]["done"] == 1
    assert fresh == [True], "a fresh worker maps a large block on its own (glibc's default)"
    assert after == [False], "a worker that resized a body takes large blocks from its heap"


def test_a_retried_body_is_not_written_twice(case, tmp_path):
    row = batch.Row(0, str(case["dir"] / "B0.obj"), str(tmp_path / "B0.obj"), "B0", 1)
    first = batch.resize_body(case["job"], row)
    stamp = os.stat(row.output).st_mtime_ns, os.stat(row.output).st_ino
    again = batch.resize_body(case["job"], row)
    assert (first["status"], again["status"]) == ("done", "skipped")
    assert (os.stat(row.output).st_mtime_ns, os.stat(row.output).st_ino) == stamp


def test_script_on_a_scheduler_resumes_and_exits_with_the_cli_codes(case):
    d = case["dir"]
    manifest = case["manifest"]("resume.csv", "resume")
    script = os.path.join(os.path.dirname(refit.__file__), "..", "refit-batch")
    args = [sys.executable, script, "--garment", str(d / "dress.obj"), "--from", str(d / "A.obj"), "--features",
            str(d / "features.json"), "--manifest", str(manifest)]
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                       silence_logs=logging.CRITICAL)
    try:
        on = ["--scheduler", cluster.scheduler_address]
        first = subprocess.run(args + on, capture_output=True, text=True)
        assert first.returncode == 4, first.stderr
        assert "%d/%d bodies done (1 failed)" % (GOOD + 1, GOOD + 1) in first.stderr
        check_outputs_equal_the_command_lines(d, "resume")
        kept = {n: os.stat(d / "resume" / n).st_mtime_ns for n in outputs_of(d / "resume")}
        os.remove(d / "resume" / "B4.obj")
        second = subprocess.run(args + on, capture_output=True, text=True)
        assert second.returncode == 4, second.stderr
        assert "1 written, %d already done, 1 failed" % (GOOD - 1) in second.stderr
        check_outputs_equal_the_command_lines(d, "resume")
        for n, t in kept.items():
            if n != "B4.obj":
                assert os.stat(d / "resume" / n).st_mtime_ns == t, n  # not written again
        summary = json.loads((d / "resume.summary.json").read_text())
        skipped = [e for e in summary["bodies"] if e["status"] == "skipped"]
        assert len(skipped) == GOOD - 1 and all("timings_ms" in e for e in skipped)  # the first run's entries
        # A garment that cannot be bound fails the whole batch as bad input, like the command line.
        (d / "broken.obj").write_text("v 0 0 0\nf 1 2 3\n")
        broken = subprocess.run(args[:3] + [str(d / "broken.obj")] + args[4:] + ["--redo"] + on,
                                capture_output=True, text=True)
        assert broken.returncode == 1, broken.stderr
        assert any(line.startswith("refit-batch: error: %s" % (d / "broken.obj")) for line in broken.stderr.splitlines())
    finally:
        cluster.close()
    usage = subprocess.run(args + ["--shard", "3/3"], capture_output=True, text=True)
    assert usage.returncode == 2 and "--shard" in usage.stderr


def test_manifest_is_read_as_the_command_line_reads_it(tmp_path):
    for i in range(3):
        subprocess.run([CLI, "generate", "--hip", str(95 + i), "--body-out", str(tmp_path / ("b %d.obj" % i))],
                       check=True, capture_output=True)
    subprocess.run([CLI, "generate", "--vertices", "1500", "--body-out", str(tmp_path / "A.obj"), "--garment-out",
                    str(tmp_path / "g.obj")], check=True, capture_output=True)
    text = ('Body,Output,Name\n# a comment\n\n  "b 0.obj" , out/zero.obj , first\n"b 1.obj",out/one.obj\n'
            '"b 2.obj","out/two, too.obj",\n')
    (tmp_path / "m.csv").write_text(text)
    rows = batch.read_manifest(str(tmp_path / "m.csv"))
    assert [r.name for r in rows] == ["first", "b 1", "b 2"]
    report = tmp_path / "r.json"
    subprocess.run([CLI, "resize", "--quiet", "--stage", "warp", "--garment", str(tmp_path / "g.obj"), "--from",
                    str(tmp_path / "A.obj"), "--to-list", str(tmp_path / "m.csv"), "--report", str(report)], check=True)
    cli = [(os.path.normpath(b["body_b"]), os.path.normpath(b["output"])) for b in json.loads(report.read_text())["bodies"]]
    assert cli == [(r.body, r.output) for r in rows]
    # Shards cover the rows exactly once, as --shard does.
    for n in (1, 2, 3, 5):
        assert sum((batch.shard_rows(rows, i, n) for i in range(n)), []) == rows

"""The Python module against the command line: same files, same options, the same
positions to the bit; errors with the command line's message; the GIL released."""
import ast
import json
import os
import pydoc
import re
import subprocess
import sys
import threading

import numpy as np
import pytest

import refit

CLI = os.environ.get("REFIT_CLI", "refit")
DATA = os.environ.get("REFIT_SHARED_DATA", "")


def positions_of(path):
    """The v lines of an OBJ as written (shortest round-trip numbers: exact doubles)."""
    return np.array([[float(t) for t in line.split()[1:4]] for line in open(path) if line.startswith("v ")])


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """A procedural mannequin pair and a 3000-vertex dress with its feature file, made by the CLI."""
    d = tmp_path_factory.mktemp("demo")
    subprocess.run([CLI, "generate", "--vertices", "3000", "--body-out", str(d / "A.obj"), "--garment-out",
                    str(d / "dress.obj"), "--features-out", str(d / "features.json")], check=True, capture_output=True)
    subprocess.run([CLI, "generate", "--hip", "104", "--belly", "6", "--body-out", str(d / "B.obj")], check=True,
                   capture_output=True)
    return d


def test_resize_equals_the_command_line(demo, tmp_path):
    out = tmp_path / "cli.obj"
    subprocess.run([CLI, "resize", "--garment", str(demo / "dress.obj"), "--from", str(demo / "A.obj"), "--to",
                    str(demo / "B.obj"), "--features", str(demo / "features.json"), "--out", str(out), "--quiet"],
                   check=True)
    g = refit.read_garment(str(demo / "dress.obj"))
    a = refit.read_body(str(demo / "A.obj"))
    f = refit.read_features(str(demo / "features.json"))
    r = refit.Binding(g, a, features=f).resize(refit.read_body(str(demo / "B.obj")))
    assert r.positions.shape == (g.vertex_count, 3)
    assert np.array_equal(r.positions, positions_of(out))
    assert set(r.report["timings_ms"]) >= {"warp", "features", "surface"}
    assert [c["name"] for c in r.report["features"]][: len(f)] == f.names
    # Written by the module, the file is the command line's, byte for byte.
    refit.write_garment(g, r.positions, str(tmp_path / "py.obj"))
    assert (tmp_path / "py.obj").read_bytes() == out.read_bytes()


def test_a_garment_read_without_its_text_writes_the_same_file(demo, tmp_path):
    source = tmp_path / "dress.obj"
    source.write_bytes((demo / "dress.obj").read_bytes())
    kept, released = refit.read_garment(str(source)), refit.read_garment(str(source), keep_text=False)
    moved = np.array(kept.positions) + [0.0, 0.5, 0.25]
    refit.write_garment(kept, moved, str(tmp_path / "kept.obj"))
    refit.write_garment(released, moved, str(tmp_path / "released.obj"))
    assert (tmp_path / "kept.obj").read_bytes() == (tmp_path / "released.obj").read_bytes()
    with open(source, "a") as f:
        f.write("# edited\n")
    with pytest.raises(refit.InputError, match="changed"):
        refit.write_garment(released, moved, str(tmp_path / "after.obj"))
    assert not (tmp_path / "after.obj").exists()


def test_body_b_as_an_array(demo):
    g = refit.read_garment(str(demo / "dress.obj"))
    a = refit.read_body(str(demo / "A.obj"))
    b = refit.read_body(str(demo / "B.obj"))
    binding = refit.Binding(g, a, stage="warp")
    from_body = binding.resize(b).positions
    from_array = binding.resize(np.array(b.vertices)).positions
    assert np.array_equal(from_body, from_array)
    assert not np.array_equal(from_body, g.positions)  # B differs from A: the warp moved the garment
    with pytest.raises(ValueError):
        g.positions[0, 0] = 1.0  # views of the engine's data are read-only


def test_errors_have_the_command_lines_message(tmp_path):
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
    with pytest.raises(refit.Error) as e:
        refit.read_garment(str(bad))
    cli = subprocess.run([CLI, "inspect", str(bad)], capture_output=True, text=True)
    assert cli.returncode == 1
    assert cli.stderr.strip() == "refit: error: " + str(e.value)
    assert str(bad) in str(e.value)
    with pytest.raises(refit.Error):
        refit.read_features(str(tmp_path / "missing.json"))


def test_threads_resize_at_once_with_the_same_result(demo):
    g = refit.read_garment(str(demo / "dress.obj"))
    binding = refit.Binding(g, refit.read_body(str(demo / "A.obj")),
                            features=refit.read_features(str(demo / "features.json")), threads=1)
    b = refit.read_body(str(demo / "B.obj"))
    expected = binding.resize(b).positions
    got = [None] * 3

    def work(i):
        got[i] = binding.resize(b).positions

    threads = [threading.Thread(target=work, args=(i,)) for i in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert all(np.array_equal(x, expected) for x in got)


KEEP_FREED_MEMORY = r"""
import sys
import numpy as np
import refit
from heap_probe import large_block_mapped_alone

demo = sys.argv[1]
g = refit.read_garment(demo + "/dress.obj")
binding = refit.Binding(g, refit.read_body(demo + "/A.obj"), features=refit.read_features(demo + "/features.json"))
b = refit.read_body(demo + "/B.obj")
before = binding.resize(b).positions
assert large_block_mapped_alone(20 << 20), "glibc maps a 20 MB block on its own by default"
assert refit.keep_freed_memory() is True
assert not large_block_mapped_alone(20 << 20), "after keep_freed_memory a 20 MB block comes from the heap"
assert np.array_equal(binding.resize(b).positions, before), "the result does not depend on it"
print("ok")
"""


def test_keep_freed_memory_keeps_large_blocks_in_the_heap(demo):
    # In a process of its own: the setting is the whole process's.
    run = subprocess.run([sys.executable, "-c", KEEP_FREED_MEMORY, str(demo)], capture_output=True, text=True,
                         env=dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path)))
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "ok"


def test_render(demo, tmp_path):
    g = refit.read_garment(str(demo / "dress.obj"))
    picture = refit.render(refit.read_body(str(demo / "A.obj")), g, path=str(tmp_path / "p.png"), width=200,
                           height=240)
    assert picture.shape == (240, 200, 3)
    assert (picture != 255).any()  # something was drawn on the white background
    assert (tmp_path / "p.png").stat().st_size > 0
    # Magnified 4x about the middle, the body fills far more of the picture.
    zoomed = refit.render(refit.read_body(str(demo / "A.obj")), g, width=200, height=240, zoom=4.0, centre=(0.5, 0.5))
    assert (zoomed != 255).any(axis=2).mean() > 2 * (picture != 255).any(axis=2).mean()
    with pytest.raises(Exception, match="zoom"):
        refit.render(refit.read_body(str(demo / "A.obj")), g, width=200, height=240, zoom=0.5)


def test_shared_dress_to_two_bodies(tmp_path):
    if not DATA or not os.path.isdir(os.path.join(DATA, "garments")):
        pytest.skip("../shared/data is absent: real-data Python test skipped")
    features = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "quality", "features", "dress.json")
    g = refit.read_garment(os.path.join(DATA, "garments", "dress_on_A_female.obj"))
    binding = refit.Binding(g, refit.read_body(os.path.join(DATA, "bodies", "A_female.obj")),
                            features=refit.read_features(features))
    for body in ("F_heavier", "F_thinner"):
        path = os.path.join(DATA, "bodies", body + ".obj")
        out = tmp_path / (body + ".obj")
        subprocess.run([CLI, "resize", "--garment", os.path.join(DATA, "garments", "dress_on_A_female.obj"), "--from",
                        os.path.join(DATA, "bodies", "A_female.obj"), "--to", path, "--features", features, "--out",
                        str(out), "--quiet"], check=True)
        r = binding.resize(refit.read_body(path))
        assert np.array_equal(r.positions, positions_of(out)), body
        assert r.report["collision"]["inside_after"] == 0


def test_follow_body_is_the_command_lines(tmp_path):
    if not DATA or not os.path.isdir(os.path.join(DATA, "garments")):
        pytest.skip("../shared/data is absent: real-data Python test skipped")
    features = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "quality", "features", "skirt.json")
    garment = os.path.join(DATA, "garments", "skirt_on_A_female.obj")
    body_a, body_b = (os.path.join(DATA, "bodies", b + ".obj") for b in ("A_female", "F_thinner"))
    binding = refit.Binding(refit.read_garment(garment), refit.read_body(body_a), features=refit.read_features(features),
                            follow_body=1.0)
    out = tmp_path / "skirt.obj"
    subprocess.run([CLI, "resize", "--garment", garment, "--from", body_a, "--to", body_b, "--features", features,
                    "--follow-body", "1", "--out", str(out), "--quiet"], check=True)
    r = binding.resize(refit.read_body(body_b))
    assert np.array_equal(r.positions, positions_of(out))
    assert any(c["followed"] for c in r.report["features"])  # the skirt's side profile sat on the hips


def test_error_classes_are_the_command_lines_exit_classes(demo, tmp_path):
    g = refit.read_garment(str(demo / "dress.obj"))
    a = refit.read_body(str(demo / "A.obj"))
    # Usage (exit 2): the values `refit resize` refuses as usage errors.
    for kwargs, flag in (({"clearance": float("nan")}, ["--clearance", "nan"]), ({"threads": -1}, ["--threads", "-1"]),
                         ({"follow_body": 11.0}, ["--follow-body", "11"]),
                         ({"units": "furlong"}, ["--units", "furlong"])):
        with pytest.raises(refit.UsageError) as e:
            refit.Binding(g, a, **kwargs)
        assert isinstance(e.value, ValueError) and e.value.exit_code == 2
        cli = subprocess.run([CLI, "resize", "--garment", str(demo / "dress.obj"), "--from", str(demo / "A.obj"),
                              "--to", str(demo / "B.obj"), "--out", str(tmp_path / "o.obj")] + flag,
                             capture_output=True, text=True)
        assert cli.returncode == e.value.exit_code, cli.stderr
    # Bad input (exit 1): the command line's code for the same file.
    with pytest.raises(refit.InputError) as e:
        refit.read_body(str(tmp_path / "missing.obj"))
    cli = subprocess.run([CLI, "inspect", str(tmp_path / "missing.obj")], capture_output=True, text=True)
    assert cli.returncode == e.value.exit_code == 1
    assert issubclass(refit.ResourceError, MemoryError) and refit.ResourceError.exit_code == 3
    # Features read for other units would be scaled wrongly: refused.
    with pytest.raises(refit.UsageError):
        refit.Binding(g, a, features=refit.read_features(str(demo / "features.json")), units="mm")


def test_garment_and_body_from_arrays_resize_as_the_files(demo):
    """What Blender hands over: positions and face lists, no file."""
    g = refit.read_garment(str(demo / "dress.obj"))
    faces = [line.split()[1:] for line in open(demo / "dress.obj") if line.startswith("f ")]
    sizes = np.array([len(f) for f in faces])
    indices = np.array([int(c.split("/")[0]) - 1 for f in faces for c in f])
    from_arrays = refit.Garment(np.array(g.positions), indices, sizes)
    assert (from_arrays.vertex_count, from_arrays.face_count) == (g.vertex_count, g.face_count)
    a, b = refit.read_body(str(demo / "A.obj")), refit.read_body(str(demo / "B.obj"))
    tris = np.array([[int(c) - 1 for c in line.split()[1:4]] for line in open(demo / "A.obj") if line.startswith("f ")])
    a2, b2 = refit.Body(np.array(a.vertices), tris), refit.Body(np.array(b.vertices), tris)
    f = refit.read_features(str(demo / "features.json"))
    expected = refit.Binding(g, a, features=f).resize(b).positions
    assert np.array_equal(refit.Binding(from_arrays, a2, features=f).resize(b2).positions, expected)
    with pytest.raises(refit.InputError, match="vertex 99999 is not one of"):
        refit.Garment(np.array(g.positions), np.array([0, 1, 99999]), np.array([3]))
    with pytest.raises(refit.InputError, match="NaN or infinite"):
        refit.Body(np.array([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]]), np.array([[0, 1, 2]]))


def test_metrics_equal_refit_compare(demo, tmp_path):
    out, rep = tmp_path / "out.obj", tmp_path / "compare.json"
    subprocess.run([CLI, "resize", "--garment", str(demo / "dress.obj"), "--from", str(demo / "A.obj"), "--to",
                    str(demo / "B.obj"), "--features", str(demo / "features.json"), "--out", str(out), "--quiet"],
                   check=True)
    subprocess.run([CLI, "compare", "--garment", str(demo / "dress.obj"), "--from", str(demo / "A.obj"), "--to",
                    str(demo / "B.obj"), "--result", str(out), "--features", str(demo / "features.json"), "--report",
                    str(rep)], check=True, capture_output=True)
    cli = json.loads(rep.read_text())
    del cli["inputs"]
    g = refit.read_garment(str(demo / "dress.obj"))
    got = refit.compare(g, positions_of(out), refit.read_body(str(demo / "A.obj")), refit.read_body(str(demo / "B.obj")),
                        features=refit.read_features(str(demo / "features.json")))
    assert got == cli
    assert got["features"] and got["penetration"]["inside"] == 0
    # metrics=True: the same numbers in the resize report, for the warp and the result.
    r = refit.Binding(g, refit.read_body(str(demo / "A.obj")), metrics=True).resize(refit.read_body(str(demo / "B.obj")))
    assert set(r.report["metrics"]) == {"warp", "result"}
    assert r.report["metrics"]["result"]["vertices"] == g.vertex_count


def test_progress_reaches_a_callback_and_can_cancel(demo):
    g = refit.read_garment(str(demo / "dress.obj"))
    stages = []
    binding = refit.Binding(g, refit.read_body(str(demo / "A.obj")), stage="warp", progress=stages.append)
    assert stages and stages[0].startswith("binding")
    stages.clear()
    binding.resize(refit.read_body(str(demo / "B.obj")), progress=stages.append)
    assert any(s.startswith("warping") for s in stages)

    def cancel(stage):
        raise KeyboardInterrupt(stage)

    with pytest.raises(KeyboardInterrupt):
        binding.resize(refit.read_body(str(demo / "B.obj")), progress=cancel)


def test_help_and_type_stubs_name_everything():
    text = pydoc.render_doc(refit, renderer=pydoc.plaintext)
    for name in refit.__all__:
        assert name in text
        assert getattr(refit, name).__doc__, name  # every public name documented
    stub = ast.parse(open(os.path.join(os.path.dirname(refit.__file__), "_refit.pyi")).read())
    stubbed = {n.name for n in stub.body if isinstance(n, (ast.ClassDef, ast.FunctionDef))}
    assert stubbed == set(refit.__all__)
    # Each stubbed function's parameters are those of the module's signature.
    for node in stub.body:
        if isinstance(node, ast.FunctionDef):
            signature = getattr(refit, node.name).__doc__.splitlines()[0]
            names = re.findall(r"(\w+): ", signature.split("(", 1)[1])
            assert [a.arg for a in node.args.args] == names, node.name


def test_the_readme_example_runs(tmp_path):
    if not DATA or not os.path.isdir(os.path.join(DATA, "garments")):
        pytest.skip("../shared/data is absent: the README's example needs it")
    root = os.path.join(os.path.dirname(__file__), "..", "..")
    readme = open(os.path.join(root, "README.md")).read()
    code = readme.split("```python\n", 1)[1].split("```", 1)[0]
    assert len(code.strip().splitlines()) <= 10
    # Run from another folder: the README's paths are relative to the repository.
    code = code.replace('"../shared/data/"', '"%s/"' % DATA).replace('"bench/', '"%s/bench/' % root)
    package = os.path.dirname(os.path.dirname(os.path.abspath(refit.__file__)))
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True,
                         env=dict(os.environ, PYTHONPATH=package))
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert [line.split()[0] for line in lines] == ["F_heavier", "F_thinner"]
    assert "'hem':" in lines[0]
    assert (tmp_path / "dress_on_F_heavier.obj").exists() and (tmp_path / "dress_on_F_thinner.obj").exists()

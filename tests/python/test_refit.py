"""The Python module against the command line: same files, same options, the same
positions to the bit; errors with the command line's message; the GIL released."""
import os
import subprocess
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


def test_render(demo, tmp_path):
    g = refit.read_garment(str(demo / "dress.obj"))
    picture = refit.render(refit.read_body(str(demo / "A.obj")), g, path=str(tmp_path / "p.png"), width=200,
                           height=240)
    assert picture.shape == (240, 200, 3)
    assert (picture != 255).any()  # something was drawn on the white background
    assert (tmp_path / "p.png").stat().st_size > 0


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

"""Mesh files: every format the library writes, read back; Mesh from arrays."""
import numpy as np
import pytest

import adamesh
from conftest import HEAD, read_bytes, run_cli

FORMATS = ["ply", "obj", "off", "stl"]


@pytest.mark.parametrize("ext", FORMATS)
def test_every_format_matches_the_cli(tmp_path, ext):
    run_cli("extract", HEAD, "--iso", 500.5, "--triangles", 3000, "--quiet",
            "-o", tmp_path / f"cli.{ext}")
    m = adamesh.extract(HEAD, 500.5, triangles=3000).mesh
    m.save(tmp_path / f"py.{ext}")
    assert read_bytes(tmp_path / f"py.{ext}") == read_bytes(tmp_path / f"cli.{ext}")
    back = adamesh.read_mesh(tmp_path / f"py.{ext}")
    assert len(back.faces) == len(m.faces)
    if ext != "stl":  # STL stores corners; merging may renumber the vertices
        np.testing.assert_allclose(back.vertices, m.vertices, rtol=1e-6, atol=1e-5)
        np.testing.assert_array_equal(back.faces, m.faces)


def test_ascii_ply(tmp_path):
    run_cli("extract", "shape:torus", "--res", 32, "--quiet", "--ascii", "-o", tmp_path / "cli.ply")
    adamesh.extract("shape:torus", res=32).mesh.save(tmp_path / "py.ply", ascii=True)
    assert read_bytes(tmp_path / "py.ply") == read_bytes(tmp_path / "cli.ply")
    assert read_bytes(tmp_path / "py.ply").startswith(b"ply\nformat ascii 1.0")


def test_mesh_from_numpy_round_trip(tmp_path):
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], dtype=np.uint16)
    m = adamesh.Mesh(v, f)
    assert len(m) == 4 and m.vertices.dtype == np.float64 and m.faces.dtype == np.int32
    st = adamesh.stats(m)
    assert st["closed"] and st["euler"] == 2
    assert st["volume"] == pytest.approx(1 / 6)
    for ext in FORMATS:
        m.save(tmp_path / f"t.{ext}")
        back = adamesh.read_mesh(tmp_path / f"t.{ext}")
        assert len(back.faces) == 4
    with pytest.raises(ValueError):
        m.vertices[0, 0] = 5  # read-only views of the mesh

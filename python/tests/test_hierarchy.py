"""Hierarchy cuts and .amh files, against the CLI's `extract --hierarchy` and `level`."""
import numpy as np
import pytest

import adamesh
from conftest import HEAD, read_bytes, run_cli


@pytest.fixture(scope="module")
def uniform():
    return adamesh.extract("shape:torus", res=40, levels=3)


def test_level_cuts_double_the_triangles(uniform):
    h = uniform.hierarchy
    base = len(uniform.base.mesh.faces)
    assert h.num_base_triangles == base
    for j in range(4):
        assert len(h.cut(level=j).faces) == base * 2 ** j
    np.testing.assert_array_equal(h.cut(level=3).faces, uniform.faces)  # M3, as extracted


def test_triangle_and_error_cuts_are_nested_and_monotone():
    r = adamesh.extract(HEAD, 500.5, triangles=20000)
    h = r.hierarchy
    budgets = [h.num_base_triangles + d for d in (0, 2000, 6000, 12000)]
    counts = [len(h.cut(triangles=n).faces) for n in budgets]
    assert all(n - 1 <= c <= n for c, n in zip(counts, budgets))  # a split adds 1 or 2
    assert counts[0] == h.num_base_triangles
    # Below the base mesh's size the cut is the base mesh.
    assert len(h.cut(triangles=10).faces) == h.num_base_triangles
    voxel = h.voxel
    errs = [len(h.cut(max_error=e * voxel).faces) for e in (4.0, 1.0, 0.5)]
    assert errs == sorted(errs)
    assert len(h.cut(splits=0).faces) == h.num_base_triangles
    assert len(h.cut(splits=10**9).faces) == len(h.cut(splits=h.num_splits).faces)
    with pytest.raises(adamesh.UsageError, match="exactly one of"):
        h.cut()
    with pytest.raises(adamesh.UsageError, match="exactly one of"):
        h.cut(triangles=10, level=1)


def test_cut_fitted_to_the_finest_mesh_without_the_volume(tmp_path):
    r = adamesh.extract(HEAD, 500.5)  # the default hierarchy: 57k triangles at its finest
    h = r.hierarchy
    plain, fitted = h.cut(triangles=20000), h.cut(triangles=20000, fit=True)
    np.testing.assert_array_equal(fitted.faces, plain.faces)
    assert not np.array_equal(fitted.vertices, plain.vertices)
    rms = [adamesh.stats(m, field=HEAD, iso=500.5)["distance"]["rms"] for m in (plain, fitted)]
    assert rms[1] < 0.85 * rms[0], rms
    # The same bytes as the CLI's `level --fit-finest`.
    h.save(tmp_path / "h.amh")
    run_cli("level", tmp_path / "h.amh", "--triangles", 20000, "--fit-finest", "--quiet",
            "-o", tmp_path / "cli.ply")
    fitted.save(tmp_path / "py.ply")
    assert read_bytes(tmp_path / "py.ply") == read_bytes(tmp_path / "cli.ply")


def test_amh_round_trip_and_cli_bytes(tmp_path):
    run_cli("extract", HEAD, "--iso", 500.5, "--triangles", 8000, "--quiet",
            "--hierarchy", tmp_path / "cli.amh")
    r = adamesh.extract(HEAD, 500.5, triangles=8000)
    r.hierarchy.save(tmp_path / "py.amh")
    assert read_bytes(tmp_path / "py.amh") == read_bytes(tmp_path / "cli.amh")
    back = adamesh.load_hierarchy(tmp_path / "py.amh")
    assert back.num_splits == r.hierarchy.num_splits
    assert back.iso == pytest.approx(500.5)
    for n in (1000, 4000, 8000):
        a, b = back.cut(triangles=n), r.hierarchy.cut(triangles=n)
        np.testing.assert_array_equal(a.vertices, b.vertices)
        np.testing.assert_array_equal(a.faces, b.faces)
        # `adamesh level` cuts the same bytes from the Python-written file.
        run_cli("level", tmp_path / "py.amh", "--triangles", n, "--quiet", "-o", tmp_path / "l.ply")
        a.save(tmp_path / "p.ply")
        assert read_bytes(tmp_path / "p.ply") == read_bytes(tmp_path / "l.ply")


def test_partial_files(tmp_path):
    r = adamesh.extract("shape:sphere", triangles=4000)
    r.hierarchy.save(tmp_path / "h.amh")
    data = read_bytes(tmp_path / "h.amh")
    (tmp_path / "cut.amh").write_bytes(data[: len(data) - 100])
    with pytest.raises(adamesh.InputError, match="cut.amh"):
        adamesh.load_hierarchy(tmp_path / "cut.amh")
    part = adamesh.load_hierarchy(tmp_path / "cut.amh", allow_partial=True)
    assert 0 < part.num_splits < r.hierarchy.num_splits

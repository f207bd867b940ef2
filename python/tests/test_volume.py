"""Volumes from numpy: the CLI's mesh on the same samples, every dtype, both axis orders,
non-contiguous arrays, signed distance fields, files."""
import numpy as np
import pytest

import adamesh
from conftest import HEAD, blob, read_bytes, run_cli, sphere_sdf


def mesh_bytes(mesh, path):
    mesh.save(path)
    return read_bytes(path)


def test_numpy_volume_gives_the_cli_mesh_of_the_same_samples(tmp_path):
    a = blob().astype(np.float32)  # array[z, y, x]
    raw = tmp_path / "blob.raw"
    a.tofile(raw)  # C order: x fastest, as raw files are read
    nz, ny, nx = a.shape
    run_cli("extract", raw, "--dims", f"{nx},{ny},{nz}", "--type", "float32", "--spacing",
            "0.5,0.75,1.25", "--iso", 100, "--triangles", 3000, "--quiet",
            "-o", tmp_path / "cli.ply", "--base", tmp_path / "cli_base.ply")
    vol = adamesh.Volume(a, order="zyx", spacing=(1.25, 0.75, 0.5))
    assert vol.shares_memory  # C-contiguous float32: no copy
    r = adamesh.extract(vol, 100, triangles=3000)
    assert mesh_bytes(r.mesh, tmp_path / "py.ply") == read_bytes(tmp_path / "cli.ply")
    assert mesh_bytes(r.base.mesh, tmp_path / "py_base.ply") == read_bytes(tmp_path / "cli_base.ply")
    assert len(r.faces) <= 3000
    assert r.vertices.dtype == np.float64 and r.vertices.shape[1] == 3
    assert r.faces.dtype == np.int32 and r.faces.shape[1] == 3
    # World units: x spans the array's last axis times 0.5.
    assert r.vertices[:, 0].max() <= (nx - 1) * 0.5 + 1e-6


def test_files_give_the_cli_mesh(tmp_path):
    run_cli("extract", HEAD, "--iso", 500.5, "--triangles", 20000, "--quiet",
            "-o", tmp_path / "cli.ply")
    want = read_bytes(tmp_path / "cli.ply")
    assert mesh_bytes(adamesh.extract(HEAD, 500.5, triangles=20000).mesh, tmp_path / "a.ply") == want
    vol = adamesh.load(HEAD)
    assert mesh_bytes(adamesh.extract(vol, 500.5, triangles=20000).mesh, tmp_path / "b.ply") == want
    # The same samples through numpy (a copy of the view) give the same mesh again.
    again = adamesh.Volume(np.array(vol.array), order="zyx", spacing=vol.spacing,
                           origin=vol.origin, direction=vol.direction)
    assert mesh_bytes(adamesh.extract(again, 500.5, triangles=20000).mesh,
                      tmp_path / "c.ply") == want


def test_loaded_volume_is_a_read_only_view():
    vol = adamesh.load(HEAD)
    assert vol.order == "zyx"
    assert vol.shape == (93, 64, 64)  # headsq: 64 x 64 x 93 samples (x, y, z)
    assert vol.dtype == np.int16
    assert not vol.array.flags.writeable
    st = vol.stats()
    assert st["min"] == vol.array.min() and st["max"] == vol.array.max()
    assert st["samples"] == vol.array.size
    with pytest.raises(ValueError):
        vol.array[0, 0, 0] = 1


@pytest.mark.parametrize("dtype", ["u1", "i1", "u2", "i2", "u4", "i4", "f4", "f8", "i8", "u8",
                                   "f2", ">i2", ">f4", "<u2"])
def test_every_dtype_gives_the_same_mesh(dtype):
    values = np.rint(blob() * 0.6)  # integers 0..120: exact in every type
    ref = adamesh.extract(adamesh.Volume(values, order="zyx"), 50.5, triangles=2000)
    vol = adamesh.Volume(values.astype(dtype), order="zyx")
    r = adamesh.extract(vol, 50.5, triangles=2000)
    np.testing.assert_array_equal(r.vertices, ref.vertices)
    np.testing.assert_array_equal(r.faces, ref.faces)
    native = np.dtype(dtype).newbyteorder("=") in {np.dtype(t) for t in
                                                   ("u1", "i1", "u2", "i2", "u4", "i4", "f4", "f8")}
    assert vol.shares_memory == (native and np.dtype(dtype).isnative)


def test_bool_volume():
    mask = blob() > 80
    r = adamesh.extract(adamesh.Volume(mask, order="zyx"), 0.5, triangles=2000)
    ref = adamesh.extract(adamesh.Volume(mask.astype(np.uint8), order="zyx"), 0.5, triangles=2000)
    np.testing.assert_array_equal(r.vertices, ref.vertices)
    assert adamesh.stats(r.mesh)["closed"]


def test_unsupported_dtype():
    with pytest.raises(adamesh.UsageError, match="unsupported sample type complex128"):
        adamesh.Volume(np.zeros((4, 4, 4), dtype=complex), order="zyx")


def test_both_axis_orders_give_the_same_mesh():
    a = blob()  # array[z, y, x]
    zyx = adamesh.Volume(a, order="zyx", spacing=(3.0, 2.0, 1.0))
    xyz_view = adamesh.Volume(a.T, order="xyz", spacing=(1.0, 2.0, 3.0))  # Fortran view
    xyz_copy = adamesh.Volume(np.ascontiguousarray(a.T), order="xyz", spacing=(1.0, 2.0, 3.0))
    assert zyx.shares_memory and xyz_view.shares_memory and not xyz_copy.shares_memory
    assert xyz_copy.shape == (32, 28, 24) and xyz_copy.spacing == (1.0, 2.0, 3.0)
    np.testing.assert_array_equal(xyz_copy.array, a.T)
    meshes = [adamesh.extract(v, 100.0, triangles=2500) for v in (zyx, xyz_view, xyz_copy)]
    for m in meshes[1:]:
        np.testing.assert_array_equal(m.vertices, meshes[0].vertices)
        np.testing.assert_array_equal(m.faces, meshes[0].faces)
    # Spacing (3, 2, 1) along (z, y, x): the object is 31 units long in x, 54 in y, 69 in z.
    ext = meshes[0].vertices.max(axis=0) - meshes[0].vertices.min(axis=0)
    assert ext[2] > ext[0]


def test_axis_order_must_be_explicit_and_valid():
    a = blob()
    with pytest.raises(TypeError):
        adamesh.Volume(a)  # no order: numpy arrays carry none
    for bad in ("yxz", "ZYX", "", None):
        with pytest.raises(adamesh.UsageError, match="order must be 'zyx'"):
            adamesh.Volume(a, order=bad)
    with pytest.raises(adamesh.UsageError, match="expected a 3-D array"):
        adamesh.Volume(a[0], order="zyx")
    with pytest.raises(adamesh.UsageError, match="spacing must be > 0"):
        adamesh.Volume(a, order="zyx", spacing=(1, 0, 1))
    with pytest.raises(adamesh.UsageError, match="wrap numpy arrays"):
        adamesh.extract(a, 100)


def test_non_contiguous_input():
    big = blob((48, 56, 64))
    for view in (big[::2, ::2, ::2], big[:, 3:40, ::-1], big[::-1, ::3, 1::2].transpose(0, 1, 2)):
        assert not view.flags.c_contiguous
        vol = adamesh.Volume(view, order="zyx")
        assert not vol.shares_memory
        ref = adamesh.Volume(np.ascontiguousarray(view), order="zyx")
        a = adamesh.extract(vol, 100.0, triangles=2000)
        b = adamesh.extract(ref, 100.0, triangles=2000)
        np.testing.assert_array_equal(a.vertices, b.vertices)
        np.testing.assert_array_equal(a.faces, b.faces)


def test_signed_distance_field_sign():
    n, radius = 48, 0.6
    h = 2.0 / (n - 1)
    sdf = sphere_sdf(n, radius)
    vol = adamesh.Volume(sdf, order="zyx", spacing=h, origin=(-1, -1, -1), inside="negative")
    assert vol.default_iso == 0.0
    r = adamesh.extract(vol, triangles=4000)  # iso 0 by default for inside="negative"
    st = adamesh.stats(r.mesh)
    assert st["closed"] and st["euler"] == 2 and st["components"] == 1
    exact = 4.0 / 3.0 * np.pi * radius ** 3
    assert st["volume"] == pytest.approx(exact, rel=0.03)  # positive: normals point out
    # Read as a scan (bright inside) the same field is inside out.
    wrong = adamesh.extract(adamesh.Volume(sdf, order="zyx", spacing=h, origin=(-1, -1, -1)),
                            0.0, triangles=4000)
    assert adamesh.stats(wrong.mesh)["volume"] == pytest.approx(-st["volume"], rel=0.05)
    # Centre of the sphere in world coordinates (x, y, z).
    np.testing.assert_allclose(r.vertices.mean(axis=0), (0.05, -0.03, 0.02), atol=0.02)


def test_volume_files_need_an_iso_value():
    with pytest.raises(adamesh.UsageError, match="quarter.nhdr: an iso-value is required"):
        adamesh.extract(HEAD)


def test_nan_samples():
    a = blob()
    a[3, 4, 5] = np.nan
    with pytest.raises(adamesh.InputError, match=r"<array>: 1 NaN/Inf samples \(first at voxel 5,4,3\)"):
        adamesh.Volume(a, order="zyx")
    vol = adamesh.Volume(a, order="zyx", nan_value=0.0)
    assert np.isnan(a[3, 4, 5])  # the caller's array is left alone
    assert vol.array[3, 4, 5] == 0.0
    assert len(adamesh.extract(vol, 100.0, triangles=1000).faces) > 0


def test_direction_and_origin_place_the_mesh():
    a = blob()
    rot = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # x -> y, y -> -x
    plain = adamesh.extract(adamesh.Volume(a.T, order="xyz"), 100.0, base_only=True)
    turned = adamesh.extract(adamesh.Volume(a.T, order="xyz", direction=rot), 100.0, base_only=True)
    np.testing.assert_allclose(turned.vertices, plain.vertices @ rot.T, atol=1e-4)
    moved = adamesh.extract(adamesh.Volume(a.T, order="xyz", origin=(10, 20, 30)), 100.0,
                            base_only=True)
    np.testing.assert_allclose(moved.vertices.min(axis=0), plain.vertices.min(axis=0) + (10, 20, 30),
                               atol=1.0)


def test_label_sets_and_the_label_map_note(tmp_path):
    # Labels 3 and 7 side by side (one box together), label 9 apart.
    a = np.zeros((24, 24, 24), dtype=np.uint8)  # [z, y, x]
    a[4:14, 4:14, 4:12] = 3
    a[4:14, 4:14, 12:18] = 7
    a[17:21, 17:21, 17:21] = 9
    raw = tmp_path / "l.raw"
    a.tofile(raw)
    opts = dict(dims=(24, 24, 24), type="uint8")
    for label in ("3,7", "3-7", [3, 7], (7, 3)):
        r = adamesh.extract(raw, label=label, **opts)
        assert r.report["base"]["components"] == 1, label
    assert adamesh.extract(raw, label=9, **opts).report["base"]["components"] == 1
    assert adamesh.extract(raw, label="3-9", **opts).report["base"]["components"] == 2
    # The raw label numbers at 0.5: the report's warnings say which set to mesh instead.
    with pytest.warns(adamesh.AdameshWarning, match="looks like a label map"):
        r = adamesh.extract(raw, 0.5, **opts)
    notes = r.report["warnings"]
    assert any("looks like a label map" in w and "`--label 3-9`" in w for w in notes), notes
    with pytest.raises(adamesh.UsageError, match="label set '7-3'"):
        adamesh.extract(raw, label="7-3", **opts)

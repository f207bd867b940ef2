"""Errors: Python exceptions (ValueError / OSError subclasses) with the CLI's one-line messages."""
import os

import numpy as np
import pytest

import adamesh
from conftest import HEAD, run_cli


def cli_message(*args):
    """The CLI's error line without its "adamesh: " prefix, and its exit code."""
    code, _, err = run_cli(*args, check=False)
    lines = err.strip().splitlines()
    assert code != 0 and len(lines) >= 1, err
    # "adamesh: <file>: <problem>", or "adamesh <command>: <problem>" for what the command line
    # named (README, "Errors and output files").
    assert lines[-1].startswith("adamesh"), err
    return code, lines[-1].split(": ", 1)[1]


def test_exception_classes():
    assert issubclass(adamesh.InputError, ValueError)
    assert issubclass(adamesh.UsageError, ValueError)
    assert issubclass(adamesh.UnsupportedError, ValueError)
    assert issubclass(adamesh.OutputError, OSError)
    for e in (adamesh.InputError, adamesh.UsageError, adamesh.UnsupportedError,
              adamesh.OutputError, adamesh.InternalError, adamesh.CancelledError):
        assert issubclass(e, adamesh.Error)


def test_missing_file_same_message_as_the_cli(tmp_path):
    missing = str(tmp_path / "missing.nrrd")
    code, msg = cli_message("extract", missing, "--iso", 1, "--quiet", "-o", tmp_path / "x.ply")
    assert code == 2
    with pytest.raises(adamesh.InputError) as e:
        adamesh.extract(missing, 1)
    assert str(e.value) == msg
    with pytest.raises(adamesh.InputError) as e:
        adamesh.load(missing)
    assert str(e.value) == msg


def test_iso_outside_the_range_same_message_as_the_cli(tmp_path):
    code, msg = cli_message("extract", HEAD, "--iso", 99999, "--quiet", "-o", tmp_path / "x.ply")
    assert code == 2 and "outside the value range" in msg
    with pytest.raises(adamesh.InputError) as e:
        adamesh.extract(HEAD, 99999)
    assert str(e.value) == msg
    with pytest.raises(ValueError):  # what a caller catching ValueError sees
        adamesh.extract(adamesh.load(HEAD), 99999)


def test_corrupt_file_same_message_as_the_cli(tmp_path):
    bad = tmp_path / "bad.nhdr"
    bad.write_text("NRRD0004\ntype: short\ndimension: 3\nsizes: 4 4\nencoding: raw\n\n")
    code, msg = cli_message("extract", bad, "--iso", 1, "--quiet", "-o", tmp_path / "x.ply")
    with pytest.raises(adamesh.Error) as e:
        adamesh.extract(bad, 1)
    assert str(e.value) == msg
    assert isinstance(e.value, ValueError)


def test_unwritable_output_is_an_oserror(tmp_path):
    target = tmp_path / "no" / "such" / "dir" / "x.ply"
    code, msg = cli_message("extract", "shape:sphere", "--res", 24, "--quiet", "--base", target)
    assert code == 4
    r = adamesh.extract("shape:sphere", res=24, base_only=True)
    with pytest.raises(adamesh.OutputError) as e:
        r.mesh.save(target)
    assert isinstance(e.value, OSError)
    # The CLI checks its outputs before any work and names the option too
    # ("--base PATH: folder ... does not exist"); the library says "PATH: folder ...".
    assert msg.endswith(str(e.value)), (msg, str(e.value))
    assert not os.path.exists(target)
    with pytest.raises(OSError):
        adamesh.extract("shape:sphere", res=24).hierarchy.save(target.with_suffix(".amh"))


def test_bad_options():
    with pytest.raises(adamesh.UsageError, match="at most one of"):
        adamesh.extract("shape:sphere", triangles=100, levels=2)
    with pytest.raises(adamesh.UsageError, match="levels must be 0..30"):
        adamesh.extract("shape:sphere", levels=31)
    with pytest.raises(adamesh.UsageError, match="triangles must be an integer >= 1"):
        adamesh.extract("shape:sphere", triangles=0)
    with pytest.raises(adamesh.UsageError, match="max_error must be > 0"):
        adamesh.extract("shape:sphere", max_error=-1.0)
    with pytest.raises(adamesh.UsageError, match="radii must be positive"):
        adamesh.extract("shape:sphere", rmax=-2)
    with pytest.raises(adamesh.InputError, match="unknown shape"):
        adamesh.extract("shape:nope")
    with pytest.raises(adamesh.UsageError, match="res must be between 2 and 4096"):
        adamesh.extract("shape:sphere", res=1)
    with pytest.raises(TypeError):
        adamesh.extract("shape:sphere", no_such_option=1)
    with pytest.raises(adamesh.UsageError, match="apply to files and shapes"):
        adamesh.extract(adamesh.Volume(np.zeros((3, 3, 3)), order="zyx"), 0.5, res=10)


def test_empty_surface():
    vol = adamesh.Volume(np.zeros((8, 8, 8), dtype=np.uint8), order="zyx")
    with pytest.raises(adamesh.InputError, match="<array>: iso-value 0.500000 is outside"):
        adamesh.extract(vol, 0.5)


def test_mesh_from_arrays_checks_indices(tmp_path):
    with pytest.raises(adamesh.UsageError, match="vertex index 3, outside 0..2"):
        adamesh.Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]])
    with pytest.raises(adamesh.UsageError, match=r"\(n, 3\)"):
        adamesh.Mesh([[0, 0], [1, 0]], [[0, 1, 1]])

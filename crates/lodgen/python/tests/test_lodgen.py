"""The Python package: arrays in and out, levels, the progressive mesh,
measured errors against the command's, exceptions, the GIL."""

import json
import subprocess
import threading
import time

import numpy as np
import pytest

import lodgen
from conftest import shared_asset, torus, write_obj


def triangle_set(vertices, faces):
    """Triangles as sorted tuples of corner coordinates, each rotated to
    start at its smallest corner (orientation kept)."""
    out = []
    for t in faces:
        corners = [tuple(np.float32(vertices[i]).tolist()) for i in t]
        k = corners.index(min(corners))
        out.append(tuple(corners[k:] + corners[:k]))
    return sorted(out)


def test_arrays_round_trip_at_full_resolution():
    v, f = torus(n=24, m=12)
    r = lodgen.simplify(v, f, levels=[1.0])
    (level,) = r.levels
    assert level.vertices.dtype == np.float64 and level.faces.dtype == np.int64
    assert level.vertices.shape == v.shape and level.faces.shape == f.shape
    assert triangle_set(level.vertices, level.faces) == triangle_set(v, f)
    assert level.errors.hausdorff < 1e-12 * level.errors.diagonal
    # float32 in, float32 out
    r32 = lodgen.simplify(v.astype(np.float32), f.astype(np.int32), levels=[1.0])
    assert r32.levels[0].vertices.dtype == np.float32


def test_levels_reach_their_counts_and_errors_grow():
    v, f = torus()
    r = lodgen.simplify(v, f, levels=[0.5, 0.1, 2000, 100])
    counts = [len(l.faces) for l in r.levels]
    # finest first, whatever the order asked
    targets = [2000, len(f) // 2, len(f) // 10, 100]
    for c, t in zip(counts, targets):
        assert t - 2 <= c <= t, (counts, targets)
    errors = [l.errors.hausdorff_percent for l in r.levels]
    assert errors == sorted(errors) and errors[-1] > 0
    assert r.note == ""
    for l in r.levels:
        assert l.faces.min() >= 0 and l.faces.max() < len(l.vertices)
        v_l, f_l = r.progressive.mesh_at_splits(l.splits)
        assert len(f_l) == len(l.faces)
    # max_error levels stay within their bounds
    r = lodgen.simplify(v, f, max_error=[0.5, 2.0])
    for l, bound in zip(r.levels, [0.5, 2.0]):
        assert l.errors.hausdorff_percent <= bound


def test_progressive_mesh_replays_to_the_input_exactly():
    v, f = torus(n=32, m=16)
    pm = lodgen.ProgressiveMesh(v, f)
    assert len(pm) > 0 and pm.applied == 0
    base_v, base_f = pm.mesh
    assert len(base_f) == pm.triangle_counts[0] < len(f)
    # Refine all the way: the input, index for index through the welding
    # maps (input vertex -> welded vertex, welded triangle -> input one).
    assert pm.refine(len(pm) + 10) == len(pm)
    fv, ff = pm.full_in_input_order()
    vm, tm = pm.vertex_map, pm.triangle_map
    np.testing.assert_array_equal(fv[vm], v.astype(np.float32))
    assert len(tm) == len(f) and sorted(tm) == list(range(len(f)))
    np.testing.assert_array_equal(ff, vm[f[tm]])
    cv, cf = pm.mesh
    assert triangle_set(cv, cf) == triangle_set(v, f)
    # Coarsen back to the base, exactly.
    assert pm.coarsen(len(pm)) == len(pm)
    bv, bf = pm.mesh
    np.testing.assert_array_equal(bv, base_v)
    np.testing.assert_array_equal(bf, base_f)
    # mesh_at and the cursor agree at every count asked.
    for t in [len(base_f), 300, 1000, len(f)]:
        k = pm._pm.splits_for_triangles(t)
        pm.seek(k)
        mv, mf = pm.mesh_at(t)
        np.testing.assert_array_equal(mf, pm.mesh[1])
        np.testing.assert_array_equal(mv, pm.mesh[0])
        assert len(mf) <= max(t, len(base_f))


def replay(pm):
    """The full mesh rebuilt from the base mesh with the split arrays alone."""
    s, faces, corners = pm.splits, pm.split_faces, pm.split_corners
    pos, tris = (np.array(a) for a in pm.mesh_at_splits(0))
    pos, tris = [tuple(p) for p in pos], [list(t) for t in tris]
    for x in s:
        assert x["v0"] == len(pos)
        pos[x["v1"]] = tuple(x["p1"])
        pos.append(tuple(x["p0"]))
        a, b = int(x["first_corner"]), int(x["first_corner"] + x["n_corners"])
        for t, slot in corners[a:b]:
            assert tris[t][slot] == x["v1"]
            tris[t][slot] = x["v0"]
        a, b = int(x["first_face"]), int(x["first_face"] + x["n_faces"])
        tris.extend(list(t) for t in faces[a:b])
    return np.array(pos, dtype=np.float32), np.array(tris, dtype=np.int64)


def test_splits_structured_array_rebuilds_every_mesh():
    v, f = torus(n=16, m=8)
    pm = lodgen.ProgressiveMesh(v, f)
    s = pm.splits
    assert s.dtype == lodgen.SPLIT_DTYPE and len(s) == len(pm)
    rv, rf = replay(pm)
    fv, ff = pm.mesh_at_splits(len(pm))
    np.testing.assert_array_equal(rv, fv)
    np.testing.assert_array_equal(rf, ff)
    assert len(ff) == len(f)
    np.testing.assert_array_equal(pm.triangle_counts, np.cumsum([len(pm.mesh_at_splits(0)[1])] + list(s["n_faces"])))


def test_splits_of_more_than_two_faces_are_whole():
    # the cow has edges of three and four faces (sheets meeting at an edge):
    # each such split restores all of them (the array once kept two)
    v, f = lodgen.read(shared_asset("cow.obj"))
    pm = lodgen.ProgressiveMesh(v, f)
    s = pm.splits
    assert s["n_faces"].max() > 2
    assert len(pm.split_faces) == s["n_faces"].sum()
    rv, rf = replay(pm)
    fv, ff = pm.mesh_at_splits(len(pm))
    np.testing.assert_array_equal(rv, fv)
    np.testing.assert_array_equal(rf, ff)


def test_trimesh_input_and_measure():
    trimesh = pytest.importorskip("trimesh")
    v, f = torus()
    mesh = trimesh.Trimesh(v, f, process=False)
    r = lodgen.simplify(mesh, levels=[0.1])
    r2 = lodgen.simplify(v, f, levels=[0.1])
    np.testing.assert_array_equal(r.levels[0].faces, r2.levels[0].faces)
    coarse = r.levels[0].to_trimesh()
    m = lodgen.measure(mesh, coarse)
    assert m.hausdorff == pytest.approx(r.levels[0].errors.hausdorff, rel=1e-9)
    assert m.rms == pytest.approx(r.levels[0].errors.rms, rel=1e-9)
    same = lodgen.measure((v, f), (v, f))
    assert same.hausdorff < 1e-12


def test_errors_match_the_command(tmp_path, lodgen_bin):
    v, f = torus()
    obj = tmp_path / "torus.obj"
    write_obj(obj, v, f)
    report = tmp_path / "r.json"
    subprocess.run(
        [lodgen_bin, str(obj), "-o", str(tmp_path / "cli.glb"), "--levels", "50%,10%,2%",
         "--report", str(report), "-q"],
        check=True,
    )
    cli = json.loads(report.read_text())["meshes"][0]["levels"]
    # Same mesh as read from the OBJ (its text round-trips float64 -> f32).
    r = lodgen.simplify(v.astype(np.float32), f, levels=[0.5, 0.1, 0.02])
    assert [len(l.faces) for l in r.levels] == [c["triangles"] for c in cli]
    for l, c in zip(r.levels, cli):
        assert l.errors.hausdorff_percent == pytest.approx(c["hausdorff_percent"], rel=1e-12)
        assert l.errors.rms_percent == pytest.approx(c["rms_percent"], rel=1e-12)
    # build() writes the command's bytes and returns its report.
    rep = lodgen.build(obj, tmp_path / "py.glb", levels=[0.5, 0.1, 0.02])
    assert (tmp_path / "py.glb").read_bytes() == (tmp_path / "cli.glb").read_bytes()
    assert rep["meshes"][0]["levels"] == cli


def test_bad_input_raises_with_the_commands_message(tmp_path, lodgen_bin):
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [np.nan, 0, 1]], dtype=np.float64)
    with pytest.raises(lodgen.LodgenError, match=r"vertex 3 has a non-finite coordinate"):
        lodgen.simplify(v, [[0, 1, 2], [0, 2, 3]])
    good = v[:3]
    with pytest.raises(lodgen.LodgenError, match=r"triangle 0 refers to vertex 5, but there are only 3 vertices"):
        lodgen.simplify(good, [[0, 1, 5]])
    with pytest.raises(lodgen.LodgenError, match=r"refers to vertex -1"):
        lodgen.simplify(good, [[0, 1, -1]])
    # an unsigned index beyond int64 is named as it is, not wrapped negative
    with pytest.raises(lodgen.LodgenError, match=r"triangle 1 refers to vertex 9223372036854775808, but there are only 3"):
        lodgen.simplify(good, np.array([[0, 1, 2], [0, 1, 2**63]], dtype=np.uint64))
    with pytest.raises(lodgen.LodgenError, match=r"shape"):
        lodgen.simplify(good[:, :2], [[0, 1, 2]])
    with pytest.raises(lodgen.LodgenError, match=r"integer"):
        lodgen.simplify(good, [[0.0, 1.0, 2.0]])
    assert issubclass(lodgen.LodgenError, ValueError)
    # Options: the command's own messages.
    vt, ft = torus(n=8, m=4)
    for opts, flag in [({"levels": [2.0]}, "--levels"), ({"tau": "abc"}, "--tau"),
                       ({"boundary": "sideways"}, "--boundary")]:
        with pytest.raises(lodgen.LodgenError) as e:
            lodgen.simplify(vt, ft, **opts)
        value = opts[next(iter(opts))]
        arg = ",".join(map(str, value)) if isinstance(value, list) else value
        cli = subprocess.run([lodgen_bin, "x.obj", flag, arg], capture_output=True, text=True)
        assert cli.returncode != 0
        first = cli.stderr.splitlines()[0].removeprefix("error: ")
        assert first.split(" [")[0].split("\n")[0] in str(e.value) or str(e.value) in cli.stderr, (str(e.value), cli.stderr)
    # A broken file: build() raises what the command prints.
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    cli = subprocess.run([lodgen_bin, str(bad), "-o", str(tmp_path / "b.glb")], capture_output=True, text=True)
    with pytest.raises(lodgen.LodgenError) as e:
        lodgen.build(bad, tmp_path / "b.glb")
    for line in cli.stderr.splitlines():
        line = line.strip().removeprefix("error: ").removeprefix("caused by: ")
        assert line in str(e.value)
    assert not (tmp_path / "b.glb").exists()


def test_measure_refuses_no_triangles_and_too_many_samples(tmp_path, lodgen_bin):
    v, f = torus(n=8, m=4)
    none = np.zeros((0, 3), dtype=np.int64)
    # (it returned an infinite distance)
    with pytest.raises(lodgen.LodgenError, match=r"measuring: mesh a has no triangles"):
        lodgen.measure((v, none), (v, f))
    with pytest.raises(lodgen.LodgenError, match=r"measuring: mesh b has no triangles"):
        lodgen.measure((v, f), (np.zeros((0, 3)), np.zeros((0, 3))))
    # the command refuses such a file too
    obj = tmp_path / "points.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    good = tmp_path / "t.obj"
    write_obj(good, v, f)
    cli = subprocess.run([lodgen_bin, "measure", str(obj), str(good)], capture_output=True, text=True)
    assert cli.returncode == 1 and "no triangles" in cli.stderr, cli.stderr
    # more samples than memory holds: an error (the process aborted)
    with pytest.raises(lodgen.LodgenError, match=r"lower --samples"):
        lodgen.measure((v, f), (v, f), samples=1e12)
    with pytest.raises(lodgen.LodgenError, match=r"lower --samples"):
        lodgen.simplify(v, f, levels=[0.5], samples=1e12)


def test_out_of_range_numbers_raise_lodgen_errors_or_clamp_as_documented():
    v, f = torus(n=12, m=6)
    # a negative option value reaches the option's own check (as "--levels=-0.5")
    with pytest.raises(lodgen.LodgenError, match=r"--levels: .*must be in \(0, 1\]"):
        lodgen.simplify(v, f, levels=[-0.5])
    with pytest.raises(lodgen.LodgenError, match=r"--tau: .*non-negative"):
        lodgen.simplify(v, f, tau="-1")
    # float64 coordinates float32 cannot hold: said so, not "non-finite"
    with pytest.raises(lodgen.LodgenError, match=r"vertex 0 .*float32"):
        lodgen.simplify(v * 1e300, f)
    with pytest.raises(lodgen.LodgenError, match=r"target_triangles"):
        lodgen.ProgressiveMesh(v, f, target_triangles=-1)
    pm = lodgen.ProgressiveMesh(v, f, target_triangles=20)
    n = len(pm)
    assert n > 0
    # counts are clamped to [0, len(pm)], as the docstrings say
    pm.seek(-5)
    assert pm.applied == 0
    pm.seek(10**30)
    assert pm.applied == n
    assert pm.refine(-3) == 0 and pm.coarsen(-3) == 0
    assert pm.coarsen(10**30) == n
    for got, want in [(pm.mesh_at_splits(-1), pm.mesh_at_splits(0)),
                      (pm.mesh_at_splits(10**30), pm.mesh_at_splits(n)),
                      (pm.mesh_at(-1), pm.mesh_at_splits(0))]:
        np.testing.assert_array_equal(got[0], want[0])
        np.testing.assert_array_equal(got[1], want[1])
    with pytest.raises(lodgen.LodgenError, match=r"integer"):
        pm.seek("three")


def test_the_gil_is_released_during_a_long_simplify():
    v, f = torus(n=400, m=200)  # 160k triangles
    ticks = [0]
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            ticks[0] += 1

    during = {}

    def work():
        before = ticks[0]
        t0 = time.perf_counter()
        lodgen.simplify(v, f, levels=[0.01])
        during["ticks"] = ticks[0] - before
        during["seconds"] = time.perf_counter() - t0

    t = threading.Thread(target=spin)
    t.start()
    try:
        work()
    finally:
        stop.set()
        t.join()
    # With the GIL held for the whole call the spinning thread would get no
    # (or a handful of) increments in between.
    assert during["seconds"] > 0.05
    assert during["ticks"] > 10000, during


def write_binary_ply(path, vertices, faces):
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(vertices)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    face = np.dtype([("n", "u1"), ("i", "<i4", (3,))])
    rows = np.empty(len(faces), dtype=face)
    rows["n"] = 3
    rows["i"] = faces
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(np.asarray(vertices, dtype="<f4").tobytes())
        f.write(rows.tobytes())


def test_ctrl_c_stops_a_long_build_and_writes_nothing(tmp_path):
    # A build of a 1.3M-triangle torus takes seconds; Ctrl-C (simulated:
    # _thread.interrupt_main) 0.3 s in must raise KeyboardInterrupt from the
    # call and stop the work, so the output never appears. (Were the work
    # left to finish, the file would be written before the exception.)
    import _thread

    v, f = torus(n=1152, m=576)
    src = tmp_path / "big.ply"
    write_binary_ply(src, v, f)
    out = tmp_path / "big.glb"
    timer = threading.Timer(0.3, _thread.interrupt_main)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            lodgen.build(src, out, levels=[0.5, 0.1])
    finally:
        timer.cancel()
    assert not out.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["big.ply"], "no temporary file left"
    # the next call is not cancelled
    small = lodgen.simplify(*torus(), levels=[0.5])
    assert len(small.levels[0].faces) == len(torus()[1]) // 2


def test_read_gives_the_arrays_the_command_reads(tmp_path):
    v, f = torus(n=12, m=6)
    write_obj(tmp_path / "t.obj", v, f)
    rv, rf = lodgen.read(tmp_path / "t.obj")
    # The OBJ reader numbers vertices in order of first use.
    assert rv.dtype == np.float32 and rf.dtype == np.int64
    assert rv.shape == v.shape and rf.shape == f.shape
    assert triangle_set(rv, rf) == triangle_set(v, f)
    with pytest.raises(lodgen.LodgenError, match=r"reading .*missing\.obj"):
        lodgen.read(tmp_path / "missing.obj")


def test_measure_off_keeps_the_levels_and_says_so():
    v, f = torus()
    on = lodgen.simplify(v, f, levels=[0.1])
    off = lodgen.simplify(v, f, levels=[0.1], measure=False)
    assert on.measured and not off.measured
    np.testing.assert_array_equal(on.levels[0].faces, off.levels[0].faces)
    np.testing.assert_array_equal(on.levels[0].vertices, off.levels[0].vertices)
    assert np.isnan(off.levels[0].errors.rms) and not np.isnan(on.levels[0].errors.rms)
    assert off.levels[0].errors.hausdorff > 0
    assert not lodgen.simplify(v, f, levels=[0.1], measure="off").measured


def test_polish_moves_the_written_levels_towards_the_input():
    v, f = torus()
    plain = lodgen.simplify(v, f, levels=[0.1, 0.02])
    polished = lodgen.simplify(v, f, levels=[0.1, 0.02], polish=True)
    for a, b in zip(plain.levels, polished.levels):
        # same triangles, other positions, closer to the torus
        np.testing.assert_array_equal(a.faces, b.faces)
        assert not np.array_equal(a.vertices, b.vertices)
        assert b.errors.rms < 0.95 * a.errors.rms, (a.errors, b.errors)
        assert b.errors.hausdorff < a.errors.hausdorff, (a.errors, b.errors)


def test_fix_worst_lowers_the_worst_spot_and_needs_the_measurement():
    v, f = torus()
    plain = lodgen.simplify(v, f, levels=[0.1, 0.02])
    fixed = lodgen.simplify(v, f, levels=[0.1, 0.02], fix_worst=True)
    one = lodgen.simplify(v, f, levels=[0.1, 0.02], fix_worst=1)
    lower = 0
    for a, b, c in zip(plain.levels, fixed.levels, one.levels):
        # same triangles; the Hausdorff distance never raised, RMS within 2 %
        np.testing.assert_array_equal(a.faces, b.faces)
        assert b.errors.hausdorff <= c.errors.hausdorff <= a.errors.hausdorff, (a, b, c)
        assert b.errors.rms <= 1.02 * a.errors.rms, (a.errors, b.errors)
        lower += b.errors.hausdorff < a.errors.hausdorff
    assert lower > 0
    with pytest.raises(lodgen.LodgenError, match="--fix-worst"):
        lodgen.simplify(v, f, levels=[0.1], fix_worst=True, measure="off")


def test_topology_change_reaches_a_count_the_topology_stops():
    # a closed torus keeps its hole: with keep_topology=True it stops above
    # 16 triangles and says why; by default (run again with joins allowed)
    # and with allow_topology_change=True it reaches the count
    v, f = torus()
    kept = lodgen.simplify(v, f, levels=[16], keep_topology=True)
    assert len(kept.levels[0].faces) > 16
    assert "allow-topology-change" in kept.note, kept.note
    for kw in ({}, {"allow_topology_change": True}):
        changed = lodgen.simplify(v, f, levels=[16], **kw)
        assert len(changed.levels[0].faces) == 16, kw
        assert changed.note == "", kw
        v_l, f_l = changed.progressive.mesh_at_splits(changed.levels[0].splits)
        assert len(f_l) == 16, kw


def test_options_are_taken_as_given_or_refused():
    v, f = torus(n=24, m=12)
    # NumPy booleans are booleans
    a = lodgen.simplify(v, f, levels=[0.1], reach=np.False_, measure=False)
    b = lodgen.simplify(v, f, levels=[0.1], reach=False, measure=False)
    np.testing.assert_array_equal(a.levels[0].faces, b.levels[0].faces)
    lodgen.simplify(v, f, levels=[0.1], polish=np.True_, measure=False)
    # what only the written files use is refused, not ignored
    for key, value in [("report", "x.json"), ("quantize", True), ("compress", "meshopt")]:
        with pytest.raises(lodgen.LodgenError, match=f"{key}= is an option of the files"):
            lodgen.simplify(v, f, **{key: value})
    with pytest.raises(lodgen.LodgenError, match="keeps every split"):
        lodgen.ProgressiveMesh(v, f, levels=[0.5])
    with pytest.raises(lodgen.LodgenError, match="cannot be used together"):
        lodgen.simplify(v, f, levels=[0.5], max_error=[0.5])
    with pytest.raises(lodgen.LodgenError, match="takes a list"):
        lodgen.simplify(v, f, levels=0.5)
    with pytest.raises(lodgen.LodgenError, match="threads= must be 1 to"):
        lodgen.build("in.obj", "out.glb", threads=5000)
    with pytest.raises(lodgen.LodgenError, match="threads= must be a whole number"):
        lodgen.build("in.obj", "out.glb", threads="2")


def test_the_note_says_why_levels_coincide():
    v, f = torus(n=6, m=4)  # 48 triangles
    r = lodgen.simplify(v, f, levels=[4, 2], measure=False)
    assert len(r.levels) == 1
    assert "fewer than 8 triangles" in r.note, r.note


def test_a_progressive_mesh_shared_by_threads():
    v, f = torus(n=48, m=24)
    pm = lodgen.ProgressiveMesh(v, f)
    errors = []

    def walk():
        try:
            for _ in range(30):
                pm.seek(len(pm))
                pm.seek(0)
        except Exception as e:  # noqa: BLE001 (any error fails the test)
            errors.append(e)

    t = threading.Thread(target=walk)
    t.start()
    while t.is_alive():
        try:
            pm.applied
            pm.mesh_at_splits(len(pm) // 2)
        except Exception as e:  # noqa: BLE001
            errors.append(e)
            break
    t.join()
    assert not errors, errors


def test_a_mesh_far_from_the_origin_keeps_its_detail():
    # a torus of radius 1 in UTM coordinates: float32 steps by 0.5 there; computed moved to
    # its first vertex (rounded) and moved back, every vertex stays where it was
    v, f = torus()
    at = np.array([512345.678, 5412345.678, 312.345])
    far = v + at
    result = lodgen.simplify(far, f, levels=[1.0, 0.1])
    full, coarse = result.levels[0], result.levels[1]
    assert full.vertices.dtype == np.float64
    assert len(full.vertices) == len(far), "vertices merged"
    gap = np.abs(np.sort(full.vertices, axis=0) - np.sort(far, axis=0)).max()
    assert gap < 1e-4, gap
    assert np.abs(coarse.vertices - at).max() < 2.0
    assert lodgen.measure((far, f), (coarse.vertices, coarse.faces)).hausdorff > 0
    assert lodgen.measure((far, f), (full.vertices, full.faces)).hausdorff < 1e-4
    pm = result.progressive
    assert np.allclose(pm.offset, np.round(far[0]))
    base, _ = pm.mesh_at_splits(0)
    assert np.abs(base - at).max() < 2.0
    replayed, _ = pm.full_in_input_order()
    assert np.abs(np.sort(replayed, axis=0) - np.sort(far, axis=0)).max() < 1e-4

"""The Python module against the command line it shares its library with: the same pixels for the
same settings, the same error messages, Ctrl-C keeping the samples done, and memory that does not
grow over a loop of renders. Run by scripts/test.sh (ILLUM_BIN names the CLI binary)."""
import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import illum

from conftest import INTERIOR, channels, cli


def test_a_render_equals_illum_render_bit_for_bit(tmp_path):
    r = illum.load(INTERIOR).render(spp=4, seed=3, integrator="full", width=40)
    assert r.beauty.dtype == np.float32 and r.beauty.shape == (30, 40, 3)
    assert set(r.aovs) == {"Direct", "IndirectDiffuse", "Reflection"}
    r.write(tmp_path / "py.exr")
    p = cli("render", INTERIOR, "--spp", 4, "--seed", 3, "--integrator", "full", "--width", 40,
            "-o", tmp_path / "cli.exr", "--quiet")
    assert p.returncode == 0, p.stderr
    a, b = channels(tmp_path / "py.exr"), channels(tmp_path / "cli.exr")
    assert a.keys() == b.keys()
    for name in a:
        assert np.array_equal(a[name], b[name], equal_nan=True), name
    # The arrays are the written planes.
    rgb = np.stack([b["R"], b["G"], b["B"]], axis=-1)
    assert np.array_equal(rgb.reshape(r.beauty.shape), r.beauty)
    assert r.metadata["illum.integrator"] == "full" and r.metadata["illum.spp"] == "4"
    assert (r.samples == 4).all() and r.spp == 4 and not r.interrupted


def test_a_dict_is_a_scene_file():
    d = json.loads(INTERIOR.read_text())
    a = illum.Scene.from_dict(d, base_dir=INTERIOR.parent).render(spp=2, width=16)
    b = illum.load(INTERIOR).render(spp=2, width=16)
    assert np.array_equal(a.beauty, b.beauty)
    assert a.resolution == (16, 12)


def test_bad_input_raises_the_message_the_cli_prints(tmp_path):
    bad = tmp_path / "bad.json"
    d = json.loads(INTERIOR.read_text())
    d["materials"]["white"]["diffuse"] = [0.75, -1, 0.72]
    bad.write_text(json.dumps(d))
    p = cli("render", bad, "-o", tmp_path / "x.exr")
    assert p.returncode != 0
    message = p.stderr.strip().splitlines()[-1].removeprefix("illum: error: ")
    assert "white" in message and "diffuse" in message
    with pytest.raises(illum.IllumError) as e:
        illum.load(bad)
    assert str(e.value) == message
    with pytest.raises(illum.IllumError) as e:
        illum.Scene.from_dict(d)
    assert "white" in str(e.value) and "diffuse" in str(e.value)
    with pytest.raises(illum.IllumError, match=r"render\(light_samples='lots'\)"):
        illum.load(INTERIOR).render(spp=1, width=8, light_samples="lots")
    with pytest.raises(illum.IllumError, match="takes no parameter"):
        illum.load(INTERIOR).render(spp=1, width=8, integrator="direct", max_depth=3)


def test_ctrl_c_returns_the_samples_done():
    # SIGINT to the process a second into a long render, as Ctrl-C would send it.
    script = textwrap.dedent(f"""
        import json, os, signal, tempfile, threading
        import numpy as np
        import illum
        # Python keeps SIGINT ignored when its parent ignored it (a job started with `&` by a
        # non-interactive shell): install the handler an interactive Python has.
        signal.signal(signal.SIGINT, signal.default_int_handler)
        s = illum.load({str(INTERIOR)!r})
        s.render(spp=1, width=32)  # kernels compiled before the clock starts
        threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        r = s.render(spp=1 << 20, width=32, integrator="path")
        # A job stopped early has no part to write, as `illum render --samples` writes none.
        threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        j = s.render(spp=1 << 20, width=32, integrator="path", samples=(0, 1 << 20))
        try:
            j.write(os.path.join(tempfile.mkdtemp(), "job.exr"))
            refused = ""
        except illum.IllumError as e:
            refused = str(e)
        print(json.dumps({{"spp": r.spp, "interrupted": r.interrupted,
                          "job_interrupted": j.interrupted, "refused": refused,
                          "finite": bool(np.isfinite(r.beauty).all()),
                          "mean": float(r.beauty.mean()),
                          "messages": illum.validation_messages()}}))
    """)
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    got = json.loads(p.stdout.strip().splitlines()[-1])
    assert got["interrupted"] and 0 < got["spp"] < 1 << 20, got
    assert got["finite"] and got["mean"] > 0, got
    assert got["messages"] == []
    assert got["job_interrupted"] and "incomplete job has no part" in got["refused"], got


def test_a_prepared_scene_edit_equals_a_fresh_load_of_the_edited_scene():
    d = json.loads(INTERIOR.read_text())
    d["camera"]["resolution"] = [40, 30]
    fresh = lambda **kw: illum.Scene.from_dict(d, base_dir=INTERIOR.parent).render(spp=2, seed=1, **kw)
    p = illum.prepare(illum.Scene.from_dict(d, base_dir=INTERIOR.parent))
    assert np.array_equal(p.render(spp=2, seed=1).beauty, fresh().beauty)
    p.set_light("ceiling_light", intensity=6, color=[1, 0.8, 0.6])
    p.set_material("red", diffuse=[0.2, 0.5, 0.7])
    a = p.render(spp=2, seed=1)
    d["lights"]["ceiling_light"].update(intensity=6, color=[1, 0.8, 0.6])
    d["materials"]["red"]["diffuse"] = [0.2, 0.5, 0.7]
    b = fresh()
    for name in ["beauty", "albedo", "normal", "depth", "emission"]:
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    for name in b.aovs:
        assert np.array_equal(a.aovs[name], b.aovs[name]), name
    # A bad edit raises the loader's message and changes nothing.
    with pytest.raises(illum.IllumError, match="intensity"):
        p.set_light("ceiling_light", intensity=-1)
    with pytest.raises(illum.IllumError, match="no lights.sun"):
        p.set_light("sun", intensity=1)
    assert np.array_equal(p.render(spp=2, seed=1).beauty, a.beauty)
    # A camera move keeps the positions relative to the camera the scene was prepared with
    # (Renderer::render_prepared): direct lighting then agrees with a fresh load to float32
    # rounding of those positions (a few ulps of the scene's size), not bit for bit.
    p.set_camera(position=[0.2, 1.4, 1.8])
    d["camera"]["position"] = [0.2, 1.4, 1.8]
    a, b = p.render(spp=2, seed=1, integrator="direct"), fresh(integrator="direct")
    assert np.allclose(a.beauty, b.beauty, rtol=1e-4, atol=1e-6)
    assert not np.array_equal(a.beauty, p.render(spp=2, seed=2, integrator="direct").beauty)


def test_a_split_render_merges_into_the_render_in_one_piece(tmp_path):
    s = illum.load(INTERIOR)
    whole = s.render(spp=8, seed=2, width=32)
    parts = [s.render(spp=8, seed=2, width=32, samples=r, crop=c)
             for r in [(0, 3), (3, 8)] for c in [(0, 0, 32, 10), (0, 10, 32, 24)]]
    assert parts[0].job == ((0, 3), (0, 0, 32, 10), (32, 24)) and whole.job is None
    merged = illum.merge(parts)
    assert np.array_equal(merged.beauty, whole.beauty)
    for name in whole.aovs:
        assert np.array_equal(merged.aovs[name], whole.aovs[name]), name
    # Through the jobs' files, as a farm does, and against `illum merge` of the same files.
    paths = [tmp_path / f"part{k}.exr" for k in range(len(parts))]
    for part, path in zip(parts, paths):
        part.write(path)
    from_files = illum.merge([str(p) for p in paths])
    assert np.array_equal(from_files.beauty, whole.beauty)
    from_files.write(tmp_path / "py.exr")
    p = cli("merge", *paths, "-o", tmp_path / "cli.exr", "--quiet")
    assert p.returncode == 0, p.stderr
    a, b = channels(tmp_path / "py.exr"), channels(tmp_path / "cli.exr")
    assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    with pytest.raises(illum.IllumError, match="not a job"):
        illum.merge([whole])
    with pytest.raises(illum.IllumError):
        illum.merge(parts[:3])


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_samples_counts_the_witness_blocks_twice():
    # 256 x 192 is 32 x 24 blocks of 8 x 8, past the 512 at which only witness blocks split their
    # samples (docs/techniques.md): one block in 16, (bx + 5 by + offset) mod 16 = 0, takes both
    # sequences' samples, twice the others'.
    s = illum.load(INTERIOR)
    whole = s.render(spp=2, seed=5, width=256, integrator="direct")
    n = whole.samples
    assert n.shape == (192, 256) and set(np.unique(n)) == {2.0, 4.0}
    blocks = n.reshape(24, 8, 32, 8).transpose(0, 2, 1, 3).reshape(24, 32, 64)
    assert (blocks == blocks[..., :1]).all()   # one count a block
    witness = blocks[..., 0] == 4.0
    assert witness.sum() == 24 * 32 // 16
    by, bx = np.nonzero(witness)
    assert len(set((bx + 5 * by) % 16)) == 1
    parts = [s.render(spp=3, seed=5, width=256, integrator="direct", samples=r)
             for r in [(0, 1), (1, 3)]]
    whole = s.render(spp=3, seed=5, width=256, integrator="direct")
    n = n / 2 * 3
    assert np.array_equal(whole.samples, n)
    assert np.array_equal(parts[0].samples, n / 3) and np.array_equal(parts[1].samples, n / 3 * 2)
    merged = illum.merge(parts)
    assert np.array_equal(merged.samples, n) and np.array_equal(merged.beauty, whole.beauty)


def test_loops_of_renders_do_not_grow_memory():
    # A direct render's film takes 656 bytes a pixel on the host (src/film/memory.rs): 2 MB at
    # 64x48. Keeping one per render would grow 2 MB a render; allow a tenth of that.
    s = illum.load(INTERIOR)
    p = illum.prepare(illum.Scene.from_dict(
        json.loads(INTERIOR.read_text()) | {"camera": {**json.loads(INTERIOR.read_text())["camera"],
                                                      "resolution": [64, 48]}},
        base_dir=INTERIOR.parent))
    for what, render, n in [("Scene.render", lambda: s.render(spp=1, width=64, integrator="direct"), 40),
                            ("Prepared.render", lambda: p.render(spp=1, integrator="direct"), 80)]:
        for _ in range(20):
            render()
        before = rss_bytes()
        for _ in range(n):
            render()
        grown = rss_bytes() - before
        print(f"{what}: resident {before / 1e6:.1f} MB after 20 renders, grew {grown / 1e6:.2f} MB over {n}")
        assert grown < n * 0.2e6, f"{what}: resident memory grew {grown / 1e6:.1f} MB over {n} renders"


def test_devices_lists_the_one_that_renders():
    names = [d["name"] for d in illum.devices()]
    r = illum.load(INTERIOR).render(spp=1, width=8)
    assert r.metadata["illum.device"] in names

"""illum.compare against what it reports: its table's relMSE recomputed here from the arrays it
returns, its images equal to separate renders with the same samples, the files `illum compare`
writes, the CLI's error messages, and Ctrl-C refusing an unfair comparison."""
import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import illum

from conftest import channels, cli

# The scene of the CLI's compare test (tests/cli.rs): a glossy sphere on a floor, a sphere light.
SCENE = {
    "camera": {"position": [0, 1, 3], "look_at": [0, 0.4, 0], "fov_y": 40, "resolution": [24, 16]},
    "materials": {"m": {"diffuse": [0.4, 0.4, 0.4],
                        "specular": [{"model": "dbrdf", "roughness": 0.2}]}},
    "shapes": {"s": {"sphere": {"center": [0, 0.4, 0], "radius": 0.4}, "material": "m"},
               "f": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [4, 4]},
                     "material": "m"}},
    "lights": {"l": {"sphere": {"center": [1, 1.5, 1], "radius": 0.2}, "intensity": 20}},
}

# relMSE's ε (src/metrics.rs, docs/techniques.md).
EPSILON = 0.01


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    scene = illum.Scene.from_dict(SCENE)
    reference = scene.render(spp=64, seed=99).beauty
    prefix = tmp_path_factory.mktemp("compare") / "cmp"
    c = illum.compare(scene, time=0.3, techniques="light,mis", reference=reference,
                      output=prefix)
    return scene, reference, prefix, c


def test_the_table_is_the_relmse_of_the_returned_images(compared):
    scene, reference, _, c = compared
    assert c.names == ["light", "mis"] and c.kind == "technique" and c.measured
    assert [row["name"] for row in c.table] == c.names
    ref = reference.astype(np.float64)
    for row in c.table:
        r = c.renders[row["name"]]
        assert row["spp"] == r.spp > 0 and r.report["spp"][-1] == r.spp
        # The independent computation: numpy's, in float64, over pixels and channels.
        relmse = np.mean((r.beauty.astype(np.float64) - ref) ** 2 / (ref ** 2 + EPSILON))
        assert row["relmse"] == pytest.approx(relmse, rel=1e-9)
        assert r.report["relmse"][-1] == row["relmse"]
        assert np.isfinite(r.report["relmse"]).all() and len(r.report["relmse"]) > 1
        assert row["efficiency"] == pytest.approx(1 / (row["relmse"] * row["seconds"]), rel=1e-12)
        # The same seed and samples give the same image as a render of its own.
        alone = scene.render(spp=r.spp, technique=row["name"])
        assert np.array_equal(alone.beauty, r.beauty), row["name"]
    # MIS is the lower-variance technique on a glossy sphere lit by a small sphere light, per
    # sample and at equal time; both are unbiased, so the difference is variance.
    light, mis = c.table
    assert mis["relmse"] * mis["spp"] < light["relmse"] * light["spp"]


def test_output_writes_what_illum_compare_writes(compared):
    _, _, prefix, c = compared
    for name in ["error.png", "strip.png"] + [f"{n}.exr" for n in c.names]:
        assert (prefix.parent / f"cmp-{name}").stat().st_size > 0, name
    for n in c.names:
        exr = channels(prefix.parent / f"cmp-{n}.exr")
        rgb = np.stack([exr["R"], exr["G"], exr["B"]], axis=-1)
        assert np.array_equal(rgb.reshape(c.renders[n].beauty.shape), c.renders[n].beauty)


def test_without_a_reference_the_half_buffers_estimate():
    c = illum.compare(illum.Scene.from_dict(SCENE), time=0.2, techniques=["mis"],
                      samples=["1/1", "4/2"])
    assert c.names == ["1-1", "4-2"] and c.kind == "run" and not c.measured
    for row in c.table:
        est = c.renders[row["name"]].report["estimated_relmse"]
        assert np.isfinite(row["relmse"]) and row["relmse"] == est[-1]


def test_bad_input_raises_the_message_the_cli_prints(tmp_path):
    path = tmp_path / "s.json"
    path.write_text(json.dumps(SCENE))
    scene = illum.load(path)
    p = cli("compare", path, "--integrators", "fool", "-o", tmp_path / "c", "--quiet")
    assert p.returncode != 0
    message = p.stderr.strip().splitlines()[-1].removeprefix("illum: error: ")
    assert "(or one of the aliases: full-nocache, full-nocaustics)" in message
    with pytest.raises(illum.IllumError) as e:
        illum.compare(scene, integrators="fool")
    assert str(e.value) == message
    with pytest.raises(illum.IllumError, match="techniques=, integrators=, samples=: mis is named twice"):
        illum.compare(scene, techniques="mis,mis")
    with pytest.raises(illum.IllumError, match=r'samples=: "4": expected L/B'):
        illum.compare(scene, samples="4")
    with pytest.raises(illum.IllumError, match=r'techniques=: unknown technique "mist"'):
        illum.compare(scene, techniques=["mist"])
    with pytest.raises(illum.IllumError, match=r"reference: an array of shape \(8, 8, 3\)"):
        illum.compare(scene, reference=np.zeros((8, 8, 3)))
    with pytest.raises(illum.IllumError, match=r"reference: expected an EXR's path or an array"):
        illum.compare(scene, reference={"not": "an image"})
    with pytest.raises(illum.IllumError, match=r"compare\(light_samples='lots'\)"):
        illum.compare(scene, light_samples="lots")
    # An output that would replace an input is refused before any work, naming both.
    reference = tmp_path / "c-mis.exr"
    scene.render(spp=1).write(reference)
    with pytest.raises(illum.IllumError,
                       match="the image output would replace the reference"):
        illum.compare(scene, techniques="mis", reference=reference, output=tmp_path / "c")


def test_ctrl_c_refuses_an_unfair_comparison_and_keeps_the_image(tmp_path):
    prefix = tmp_path / "c"
    script = textwrap.dedent(f"""
        import os, signal, threading
        import illum
        # As an interactive Python has it, even when started with SIGINT ignored (`&`).
        signal.signal(signal.SIGINT, signal.default_int_handler)
        s = illum.Scene.from_dict({SCENE!r})
        threading.Timer(1.5, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        try:
            illum.compare(s, time=60, techniques="mis", output={str(prefix)!r})
            print("finished")
        except KeyboardInterrupt as e:
            print("interrupted:", e)
    """)
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert "interrupted: illum.compare: stopped during mis" in p.stdout, p.stdout
    # The samples done are kept, as `illum compare` keeps them; no table, curves or strip.
    assert f"wrote {prefix}-mis.exr" in p.stdout, p.stdout
    exr = channels(tmp_path / "c-mis.exr")
    assert np.isfinite(exr["R"]).all() and exr["R"].mean() > 0
    assert not (tmp_path / "c-error.png").exists()

"""AppearanceModel: built, saved, loaded, reconstructed, interpolated and completed as
``surfcap appearance build | reconstruct | interpolate | complete`` do, on 64x64 maps generated
from the real head scan (6 frames, one with an occlusion hole). The models and the maps are
compared with the command's files, to the bit; bad arguments name the argument."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import surfcap

PIL = pytest.importorskip("PIL.Image")


@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("appearance")


def run(exe: Path, *args) -> dict:
    p = subprocess.run([str(exe), "--json", *map(str, args)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


@pytest.fixture(scope="module")
def generated(data: Path, surfcap_bin: Path, workdir: Path) -> Path:
    out = workdir / "gen"
    run(surfcap_bin, "appearance", "generate", "--data", data, "--frames", "6", "--seed", "3", "--size", "64",
        "--hole-fraction", "0.2", "-o", out)
    return out


@pytest.fixture(scope="module")
def cli_model(generated: Path, surfcap_bin: Path, workdir: Path):
    out = workdir / "cli.appearance"
    summary = run(surfcap_bin, "appearance", "build", generated, "--cache-dir", workdir / "cli-cache", "-o", out)
    return out, summary


def png(path: Path) -> np.ndarray:
    return np.asarray(PIL.open(path).convert("RGB"))


def holed(generated: Path) -> list:
    return json.loads((generated / "frames.json").read_text())["hole_frames"]


def summary_numbers(s: dict) -> dict:
    return {k: v for k, v in s.items() if k not in ("model", "stages", "seconds")}


def test_build_from_the_folder_equals_the_command(generated, cli_model, workdir, caplog):
    cli_dir, cli_summary = cli_model
    model = surfcap.AppearanceModel.build(generated, cache_dir=workdir / "py-cache")
    assert "left out of the model" in caplog.text, "the note about holed frames is logged"
    assert model.n_frames == 6 - len(holed(generated))
    assert model.shape == (64, 64)
    assert model.mask.dtype == np.bool_ and model.mask.shape == (64, 64)
    r = model.report
    assert isinstance(r, surfcap.reports.AppearanceBuildReport)
    assert summary_numbers(r.to_dict()) == summary_numbers(cli_summary)
    # Saved, its files are the command's, byte for byte.
    saved = workdir / "py.appearance"
    model.save(saved)
    files = sorted(p.name for p in cli_dir.iterdir())
    assert {"model.json", "eigen_textures.npy", "eigen_warps.npy", "texture_coefficients.npy"} <= set(files)
    for f in files:
        assert (saved / f).read_bytes() == (cli_dir / f).read_bytes(), f


def test_build_shares_the_commands_flow_cache_and_output_writes_its_folder(generated, cli_model, workdir):
    cli_dir, _ = cli_model
    cache = workdir / "cli-cache"
    before = sorted(p.name for p in cache.iterdir())
    assert before, "the command cached its flows"
    out = workdir / "written.appearance"
    model = surfcap.AppearanceModel.build(generated, cache_dir=cache, output=out)
    assert sorted(p.name for p in cache.iterdir()) == before, "every flow read from the command's cache"
    assert model.report.model == str(out)
    for f in sorted(p.name for p in cli_dir.iterdir()):
        assert (out / f).read_bytes() == (cli_dir / f).read_bytes(), f
    with pytest.raises(surfcap.SurfcapError, match="template.obj"):
        surfcap.AppearanceModel.build(generated, cache=False, output=generated / "template.obj")


def test_maps_as_an_array_build_the_same_model(generated, cli_model, workdir):
    cli_dir, _ = cli_model
    frames = json.loads((generated / "frames.json").read_text())
    keep = [f for k, f in enumerate(frames["frame_files"]) if k not in frames["hole_frames"]]
    maps = np.stack([png(generated / f) for f in keep])
    assert maps.shape == (len(keep), 64, 64, 3) and maps.dtype == np.uint8
    names = [Path(f).stem for f in keep]
    model = surfcap.AppearanceModel.build(maps, generated / "template.obj", names=names, cache=False)
    assert model.names == names
    saved = workdir / "array.appearance"
    model.save(saved)
    for f in sorted(p.name for p in cli_dir.iterdir()):
        assert (saved / f).read_bytes() == (cli_dir / f).read_bytes(), f


def test_reconstruct_interpolate_and_complete_equal_the_command(generated, cli_model, surfcap_bin, workdir):
    cli_dir, _ = cli_model
    model = surfcap.AppearanceModel.load(cli_dir, cache_dir=workdir / "py-cache")
    name = model.names[1]
    for components in (None, 3):
        out = workdir / f"cli-rec-{components}.png"
        extra = [] if components is None else ["--components", components]
        run(surfcap_bin, "appearance", "reconstruct", cli_dir, "--frame", name, *extra, "-o", out)
        ours = model.reconstruct(name, components=components)
        assert ours.dtype == np.uint8 and ours.shape == (64, 64, 3)
        np.testing.assert_array_equal(ours, png(out))
        np.testing.assert_array_equal(model.reconstruct(1, components=components), ours)
    written = workdir / "py-rec.png"
    model.reconstruct(name, output=written)
    assert written.read_bytes() == (workdir / "cli-rec-None.png").read_bytes()

    a, b = model.names[0], model.names[2]
    out = workdir / "cli-int.png"
    run(surfcap_bin, "appearance", "interpolate", cli_dir, "--frames", f"{a}=0.25,{b}=0.75", "-o", out)
    np.testing.assert_array_equal(model.interpolate([a, b], [0.25, 0.75]), png(out))
    out = workdir / "cli-int-equal.png"
    run(surfcap_bin, "appearance", "interpolate", cli_dir, "--frames", f"{a},{b}", "-o", out)
    np.testing.assert_array_equal(model.interpolate([a, b]), png(out))

    frames = json.loads((generated / "frames.json").read_text())
    hole_map = generated / frames["frame_files"][frames["hole_frames"][0]]
    for keep in (False, True):
        out = workdir / f"cli-done-{keep}.png"
        extra = ["--keep-observed"] if keep else []
        r = run(surfcap_bin, "appearance", "complete", cli_dir, hole_map, *extra, "--cache-dir", workdir / "cli-cache",
                "-o", out)
        assert r["missing_texels"] > 0
        np.testing.assert_array_equal(model.complete(hole_map, keep_observed=keep), png(out))
        # The map as an array and its observed texels as booleans: the same completion.
        texture = png(hole_map)
        observed = texture.any(axis=2)
        np.testing.assert_array_equal(model.complete(texture, observed, keep_observed=keep), png(out))


def test_bad_arguments_name_the_argument(generated, cli_model, workdir):
    cli_dir, _ = cli_model
    model = surfcap.AppearanceModel.load(cli_dir, cache=False)
    with pytest.raises(surfcap.SurfcapError, match=r"frame \"walk:3\": the model has no frame of that name"):
        model.reconstruct("walk:3")
    with pytest.raises(IndexError, match=r"frame 99: the model has frames 0 to"):
        model.reconstruct(99)
    with pytest.raises(ValueError, match=r"weights: 1 weights for 2 frames"):
        model.interpolate([0, 1], [1.0])
    with pytest.raises(surfcap.SurfcapError, match=r"texture: the map is 32x32: expected 64x64 like the model's"):
        model.complete(np.zeros((32, 32, 3), np.uint8))
    with pytest.raises(surfcap.SurfcapError, match=r"observed: the observed-texel image is 2x3: expected 64x64"):
        model.complete(np.zeros((64, 64, 3), np.uint8), np.zeros((3, 2), bool))
    with pytest.raises(TypeError, match=r"texture: expected a PNG/JPEG path or an \(H, W, 3\) uint8 array"):
        model.complete(np.zeros((64, 64, 3), np.float32))
    with pytest.raises(ValueError, match=r"warping: bend: expected poisson"):
        surfcap.AppearanceModel.build(generated, warping="bend", cache=False)
    with pytest.raises(ValueError, match=r"components: 1: expected at least 2"):
        surfcap.AppearanceModel.build(generated, components=1, cache=False)
    with pytest.raises(ValueError, match=r"maps: shape \[2, 64, 64\], expected \(frames, height, width, 3\)"):
        surfcap.AppearanceModel.build(np.zeros((2, 64, 64), np.uint8), generated / "template.obj", cache=False)
    with pytest.raises(TypeError, match=r"mesh: required with an array of maps"):
        surfcap.AppearanceModel.build(np.zeros((2, 64, 64, 3), np.uint8), cache=False)
    empty = workdir / "no-mesh"
    empty.mkdir()
    with pytest.raises(surfcap.SurfcapError, match=r"no template.obj in the folder"):
        surfcap.AppearanceModel.build(empty, cache=False)
    with pytest.raises(surfcap.SurfcapError, match=r"model.json"):
        surfcap.AppearanceModel.load(workdir / "no-such-model")

"""VariationModel: trained, saved, loaded and sampled as ``surfcap vary train | sample`` do, on a
small mannequin (1,000 vertices) driven by two CMU clips (16_15 walk, 16_36 jog), with few GPDM
iterations and short chains. The model's fits, the variants' positions (to the bit) and the
reports' numbers are compared with the command's files; bad arguments name the argument."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import surfcap

ITERATIONS = "25"
SAMPLING = dict(count=2, seed=3, warmup=20, thin=2)
SAMPLING_ARGS = ["--count", "2", "--seed", "3", "--warmup", "20", "--thin", "2"]


@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("vary")


@pytest.fixture(scope="module")
def mannequin(data: Path, surfcap_bin: Path, workdir: Path) -> Path:
    """The mannequin moved by the walk and the jog, as a subject cache."""
    import subprocess

    out = workdir / "cmu.subject"
    bvh = [str(data / "cmu_bvh" / f"{c}.bvh") for c in ("16_15", "16_36")]
    p = subprocess.run(
        [str(surfcap_bin), "--quiet", "make", "mannequin", "--bvh", *bvh, "--vertices", "1000", "-o", str(out)],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 0, p.stderr
    return out


@pytest.fixture(scope="module")
def cli_model(mannequin: Path, surfcap_bin: Path, workdir: Path) -> Path:
    """The command's model: walk and jog, the jog the reference, their blend at 0.5."""
    import subprocess

    out = workdir / "cli-model"
    p = subprocess.run(
        [str(surfcap_bin), "--quiet", "vary", "train", str(mannequin), "--sequences", "16_15,16_36",
         "--reference", "16_36", "--blend", "16_15:16_36", "--iterations", ITERATIONS, "-o", str(out)],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 0, p.stderr
    return out


def report_json(folder: Path) -> dict:
    return json.loads((folder / "report.json").read_text())


def fits(report: dict) -> list:
    """Every part's fit without its time."""
    return [{k: v for k, v in p.items() if k != "seconds"} for p in report["parts"]]


def numbers(report: dict) -> dict:
    """A sampling report's numbers: the chains without their times, the variants without files."""
    chains = [{k: v for k, v in c.items() if k != "seconds"} for c in report["chains"]]
    variants = [{k: v for k, v in v.items() if k != "file"} for v in report["variants"]]
    return {"chains": chains, "variants": variants, "learnt": report["learnt"], "blend": report.get("blend")}


def same_as_glb(variant: surfcap.Subject, glb: Path, tmp: Path) -> None:
    """The variant equals the command's glb to the bit: exported as glb it gives the same
    bytes (the glb stores the positions in its own axes, so reading it back rounds them)."""
    mine = tmp / f"mine-{glb.name}"
    variant.export(mine, force=True)
    assert mine.read_bytes() == glb.read_bytes(), glb.name
    np.testing.assert_allclose(variant.positions, surfcap.Subject.load(glb, cache=False).positions, atol=1e-6)


def test_training_learns_the_commands_model_and_save_writes_what_the_command_reads(
    mannequin, cli_model, cli, workdir
):
    subject = surfcap.Subject.load(mannequin, cache=False)
    model = surfcap.VariationModel.train(
        subject, ["16_15", "16_36"], reference="16_36", blend=[("16_15", "16_36")], iterations=int(ITERATIONS)
    )
    assert model.sequences == ["16_15", "16_36", "16_15+16_36@0.5"]
    assert (model.reference, model.frames, len(model.parts)) == ("16_36", 47, 5)
    r = model.report
    assert isinstance(r, surfcap.reports.VariationTrainReport)
    assert "model" not in r, "nothing written yet"
    expected = report_json(cli_model)
    assert fits(r.to_dict()) == fits(expected), "the same fits as the command, to the bit"
    assert [s.to_dict() for s in r.sequences] == expected["sequences"]

    # Saved, the command samples from it exactly as from its own model.
    saved = workdir / "py-model"
    model.save(saved)
    assert report_json(saved)["model"] == str(saved)
    assert fits(report_json(saved)) == fits(expected)
    ours, theirs = workdir / "from-py-model", workdir / "from-cli-model"
    for m, out in ((saved, ours), (cli_model, theirs)):
        cli("--quiet", "vary", "sample", m, "--sequence", "16_15", *SAMPLING_ARGS, "-o", out)
    for k in (1, 2):
        name = f"16_15-variant-{k}.glb"
        assert (ours / name).read_bytes() == (theirs / name).read_bytes(), name
    # Without --force a folder surfcap did not write is left alone.
    user = workdir / "user-folder"
    user.mkdir()
    (user / "mine.txt").write_text("mine")
    with pytest.raises(surfcap.SurfcapError, match="did not write"):
        model.save(user)
    assert sorted(p.name for p in user.iterdir()) == ["mine.txt"]


def test_variants_of_a_sequence_equal_the_commands_to_the_bit(cli_model, cli, workdir):
    out = workdir / "cli-walk"
    cli("--quiet", "vary", "sample", cli_model, "--sequence", "16_15", *SAMPLING_ARGS, "-o", out)
    model = surfcap.VariationModel.load(cli_model, cache=False)
    assert model.report.reference == "16_36"
    variants, report = model.sample("16_15", **SAMPLING)
    assert isinstance(report, surfcap.reports.VariationSampleReport)
    assert len(variants) == 2
    for k, v in enumerate(variants, start=1):
        assert v.sequences == [f"16_15~{k}"]
        assert v.positions.dtype == np.float32 and v.positions.shape == (117, model.n_vertices, 3)
        same_as_glb(v, out / f"16_15-variant-{k}.glb", workdir)
    assert numbers(report.to_dict()) == numbers(report_json(out))
    assert "view" not in report and "file" not in report.variants[0]
    assert report.model == str(cli_model)
    assert not np.array_equal(variants[0].positions, variants[1].positions), "two variants differ"

    # The switches reach the sampling as the command's do.
    for flags, kw in (
        (["--carry-pins"], {"carry_pins": True}),
        (["--no-learnt-stretch"], {"no_learnt_stretch": True}),
        (["--deviation-smoothing", "0"], {"deviation_smoothing": 0}),
    ):
        switched = workdir / f"cli-walk{flags[0]}"
        cli("--quiet", "vary", "sample", cli_model, "--sequence", "16_15", *SAMPLING_ARGS, *flags, "-o", switched)
        other, _ = model.sample("16_15", **SAMPLING, **kw)
        same_as_glb(other[0], switched / "16_15-variant-1.glb", workdir)
        assert not np.array_equal(other[0].positions, variants[0].positions), flags

    # output= writes the command's folder: the same glb bytes and report numbers.
    written = workdir / "py-walk"
    _, report = model.sample("16_15", **SAMPLING, output=written)
    for k in (1, 2):
        name = f"16_15-variant-{k}.glb"
        assert (written / name).read_bytes() == (out / name).read_bytes(), name
    assert numbers(report_json(written)) == numbers(report_json(out))
    assert report.variants[0].file == str(written / "16_15-variant-1.glb")
    assert report.view.startswith("surfcap view ")


def test_blended_variants_equal_the_commands_to_the_bit(cli_model, cli, workdir):
    out = workdir / "cli-blend"
    cli("--quiet", "vary", "sample", cli_model, "--blend", "16_15:16_36:0.25", *SAMPLING_ARGS, "-o", out)
    model = surfcap.VariationModel.load(cli_model, cache=False)
    variants, report = model.sample(blend=("16_15", "16_36", 0.25), **SAMPLING)
    assert report.blend.upper_sequence == "16_15+16_36@0.5"
    for k, v in enumerate(variants, start=1):
        assert v.sequences == [f"16_15+16_36@0.25~{k}"]
        same_as_glb(v, out / f"16_15-16_36-0.25-variant-{k}.glb", workdir)
    assert numbers(report.to_dict()) == numbers(report_json(out))


def test_bad_arguments_name_the_argument(mannequin, cli_model, workdir):
    model = surfcap.VariationModel.load(cli_model, cache=False)
    with pytest.raises(surfcap.SurfcapError, match=r"no learnt sequence \"walk\": the model has 16_15, 16_36"):
        model.sample("walk")
    with pytest.raises(surfcap.SurfcapError, match=r"--count 0: expected a whole number from 1 to 1000"):
        model.sample("16_15", count=0)
    with pytest.raises(surfcap.SurfcapError, match=r"--deviation-smoothing 1001: expected a whole number from 0 to 1000"):
        model.sample("16_15", deviation_smoothing=1001)
    with pytest.raises(surfcap.SurfcapError, match=r"leapfrog steps per body part, above the 2000000 allowed"):
        model.sample("16_15", count=1000, thin=100)
    with pytest.raises(ValueError, match=r"start: \"middle\": expected learnt or mean"):
        model.sample("16_15", start="middle")
    with pytest.raises(ValueError, match=r"path: \"air\": expected source, contacts or sampled"):
        model.sample("16_15", path="air")
    with pytest.raises(ValueError, match=r"blend: the weight 1.5"):
        model.sample(blend=("16_15", "16_36", 1.5))
    with pytest.raises(TypeError, match="give one, not both"):
        model.sample("16_15", blend=("16_15", "16_36", 0.5))
    with pytest.raises(ValueError, match="carry_pins with hold_hips"):
        model.sample("16_15", carry_pins=True, hold_hips=True)
    with pytest.raises(TypeError, match="expected sequence=NAME or blend"):
        model.sample()
    with pytest.raises(surfcap.SurfcapError, match="model.json"):
        surfcap.VariationModel.load(workdir / "no-such-model")

    subject = surfcap.Subject.load(mannequin, cache=False)
    with pytest.raises(surfcap.SurfcapError, match=r"--sequences: .* has no sequence \"run\"; it has 16_15, 16_36"):
        surfcap.VariationModel.train(subject, ["16_15", "run"])
    with pytest.raises(surfcap.SurfcapError, match=r"--latent-dim 0: expected a whole number from 1 to 10"):
        surfcap.VariationModel.train(subject, latent_dim=0)
    with pytest.raises(surfcap.SurfcapError, match=r"--blend-weights 1: expected a number strictly between 0 and 1"):
        surfcap.VariationModel.train(subject, blend=[("16_15", "16_36")], blend_weights=[1.0])
    with pytest.raises(surfcap.SurfcapError, match=r"--reference: \"run\" is not one of the learnt sequences"):
        surfcap.VariationModel.train(subject, ["16_15", "16_36"], reference="run")
    with pytest.raises(surfcap.SurfcapError, match=r"no-parts.json"):
        surfcap.VariationModel.train(subject, ["16_15", "16_36"], parts=workdir / "no-parts.json")

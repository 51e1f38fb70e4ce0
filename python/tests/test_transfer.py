"""Motion transfer from Python between two KayKit characters (the knight's walk onto the
barbarian, the barbarian's own clip the truth): ``TransferModel.train`` writes the model folder
``surfcap transfer train`` writes, byte for byte; ``apply`` plays the animation ``surfcap transfer
apply`` writes, to the bit, with the same report numbers; the command reads what ``save``
writes and ``load`` reads what the command writes; bad arguments are named."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import surfcap

# Eight key pairs on Walking_A, densified; Walking_C is the unseen motion transferred.
PAIRS = [(f"knight_Walking_A:{k * 32 // 7}", f"barbarian_Walking_A:{k * 32 // 7}") for k in range(8)]


@pytest.fixture(scope="module")
def characters(data: Path, surfcap_bin: Path, tmp_path_factory) -> dict:
    """The knight and the barbarian, Walking_A and Walking_C each, as subject caches, and the
    pairs CSV."""
    import subprocess

    d = tmp_path_factory.mktemp("kaykit")
    out = {}
    for who in ["knight", "barbarian"]:
        subject = d / f"{who}.subject"
        clips = [str(data / "kaykit_adventurers" / f"{who}_{c}") for c in ["Walking_A", "Walking_C"]]
        subprocess.run([str(surfcap_bin), "--quiet", "import", *clips, "--name", who, "-o", str(subject)], check=True)
        out[who] = subject
    pairs = d / "pairs.csv"
    pairs.write_text("source,target\n" + "".join(f"{a}, {b}\n" for a, b in PAIRS))
    out["pairs"] = pairs
    return out


def same_files(a: Path, b: Path, names=None):
    """The files `names` (default: every file under `a`) have the same bytes under `a` and `b`."""
    if names is None:
        names = sorted(str(p.relative_to(a)) for p in a.rglob("*") if p.is_file())
        assert names and names == sorted(str(p.relative_to(b)) for p in b.rglob("*") if p.is_file())
    for n in names:
        assert (a / n).read_bytes() == (b / n).read_bytes(), n


def test_gp_train_and_apply_equal_the_commands_to_the_bit(cli, characters, tmp_path, cache_dir):
    knight, barbarian, pairs = characters["knight"], characters["barbarian"], characters["pairs"]
    cli_model = tmp_path / "cli-model"
    trained = cli("transfer", "train", "--source", knight, "--target", barbarian, "--pairs", pairs,
                  "--cache-dir", cache_dir, "-o", cli_model, json_out=True)
    py_cache = tmp_path / "py-cache"
    py_cache.mkdir()
    src = surfcap.Subject.load(knight, cache_dir=py_cache)
    tgt = surfcap.Subject.load(barbarian, cache=False)
    model = surfcap.TransferModel.train(src, tgt, pairs)
    assert model.method == "gp" and (model.source_name, model.target_name) == ("knight", "barbarian")
    r = model.report
    assert isinstance(r, surfcap.reports.TransferTrainReport)
    for k in ["pairs", "key_pairs", "densified", "sequence_pairs", "source_sequences", "target_sequences", "kernel",
              "components", "parts", "displacement"]:
        assert r.to_dict()[k] == trained[k], k
    assert r.cached is False
    # The model folder the command writes, byte for byte.
    py_model = tmp_path / "py-model"
    model.save(py_model)
    same_files(cli_model, py_model, ["model.json", "target_training.npy"])
    assert json.loads((py_model / "report.json").read_text())["model"] == str(py_model)
    # Pairs as a list of frames give the same model; the second training comes from the cache.
    again = surfcap.TransferModel.train(src, tgt, PAIRS, output=tmp_path / "again")
    assert again.report.cached is True
    same_files(cli_model, tmp_path / "again", ["model.json", "target_training.npy"])

    # The unseen Walking_C, with the barbarian's own Walking_C as the truth.
    cli_out = tmp_path / "cli-walk"
    cli("transfer", "apply", cli_model, "--motion", f"{knight}:knight_Walking_C", "--truth",
        f"{barbarian}:barbarian_Walking_C", "--format", "npy", "-o", cli_out)
    want = json.loads((tmp_path / "cli-walk.report.json").read_text())
    walk, report = model.apply(src, "knight_Walking_C", truth=(tgt, "barbarian_Walking_C"))
    assert isinstance(report, surfcap.reports.TransferApplyReport)
    assert walk.sequences == ["knight_Walking_C-as-barbarian"] and walk.positions.shape == (49, 2095, 3)
    py_out = tmp_path / "py-walk"
    walk.export(py_out, "npy")
    same_files(cli_out, py_out)
    got = report.to_dict()
    for k in ["method", "source", "target", "frames", "reconstruction", "correction", "nearest", "parts",
              "edge_length_distortion", "per_frame"]:
        assert got[k] == want[k], k
    for k in ["target_height", "rms", "rms_percent", "nearest_training_pose_rms", "nearest_training_poses"]:
        assert got["accuracy"][k] == want["accuracy"][k], k
    assert report.motion == "knight:knight_Walking_C" and report.written == []
    # The command's model loaded, applied with output=: the command's bytes again.
    loaded = surfcap.TransferModel.load(cli_model)
    assert loaded.report.pairs == trained["pairs"]
    out = tmp_path / "loaded-walk"
    _, r2 = loaded.apply(src, "knight_Walking_C", output=out, format="npy")
    same_files(cli_out, out)
    assert r2.accuracy is None and r2.model == str(cli_model) and r2.written
    # The command applies the model `save` wrote.
    cli_out2 = tmp_path / "cli-walk2"
    cli("transfer", "apply", py_model, "--motion", f"{knight}:knight_Walking_C", "--format", "npy", "-o", cli_out2)
    same_files(cli_out, cli_out2)


def test_baran_train_and_apply_equal_the_commands_to_the_bit(cli, characters, tmp_path):
    knight, barbarian, pairs = characters["knight"], characters["barbarian"], characters["pairs"]
    cli_model = tmp_path / "cli-baran"
    cli("transfer", "train", "--method", "baran", "--source", knight, "--target", barbarian, "--pairs", pairs,
        "-o", cli_model)
    src = surfcap.Subject.load(knight, cache=False)
    tgt = surfcap.Subject.load(barbarian, cache=False)
    model = surfcap.TransferModel.train(src, tgt, pairs, method="baran", output=tmp_path / "py-baran")
    assert model.method == "baran" and model.report.key_pairs == 8
    same_files(cli_model, tmp_path / "py-baran", ["model.json", "source_keys.npy", "target_keys.npy"])
    cli_out = tmp_path / "cli-walk"
    cli("transfer", "apply", cli_model, "--motion", f"{knight}:knight_Walking_C", "--format", "npy", "-o", cli_out)
    walk, report = model.apply(src, "knight_Walking_C")
    walk.export(tmp_path / "py-walk", "npy")
    same_files(cli_out, tmp_path / "py-walk")
    assert report.method == "baran" and report.reconstruction == "baran"


def test_bad_arguments_are_named(characters, tmp_path):
    src = surfcap.Subject.load(characters["knight"], cache=False)
    tgt = surfcap.Subject.load(characters["barbarian"], cache=False)
    with pytest.raises(ValueError, match="kernel"):
        surfcap.TransferModel.train(src, tgt, PAIRS, kernel="rbf")
    with pytest.raises(ValueError, match='method "procrustes": expected gp or baran'):
        surfcap.TransferModel.train(src, tgt, PAIRS, method="procrustes")
    with pytest.raises(ValueError, match=r"pairs\[0\] source"):
        surfcap.TransferModel.train(src, tgt, [("knight_Walking_A:99", "barbarian_Walking_A:0")])
    bad = tmp_path / "bad.csv"
    bad.write_text("knight_Walking_A:0\n")
    with pytest.raises(surfcap.SurfcapError, match="bad.csv line 1"):
        surfcap.TransferModel.train(src, tgt, bad)
    model = surfcap.TransferModel.train(src, tgt, PAIRS, method="baran")
    with pytest.raises(surfcap.SurfcapError, match='sequence: knight has no sequence "nope"'):
        model.apply(src, "nope")
    with pytest.raises(surfcap.SurfcapError, match="barbarian: 2095 vertices, but the model"):
        model.apply(tgt, "barbarian_Walking_C")
    with pytest.raises(surfcap.SurfcapError, match="truth barbarian:barbarian_Walking_A: 33 frames"):
        model.apply(src, "knight_Walking_C", truth=(tgt, "barbarian_Walking_A"))
    with pytest.raises(ValueError, match="reconstruction"):
        model.apply(src, "knight_Walking_C", reconstruction="blend")
    with pytest.raises(surfcap.SurfcapError, match="model.json"):
        surfcap.TransferModel.load(tmp_path)
    # A folder surfcap did not write is never replaced.
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    with pytest.raises(surfcap.SurfcapError):
        model.save(mine)
    assert (mine / "notes.txt").read_text() == "keep"

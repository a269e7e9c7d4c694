"""What lifted a result: every written record's ``model_info`` (``Lifter.provenance``) names the version, each
network's checkpoint sha256 (what ``sha256sum`` prints), the flip test as it ran, and int8 (a developer trial: a
result JSON did not say whether the flip test was on, nor which ``--weights file.pt`` made it)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from conftest import tiny_lifter

import lifter
from lifter import Lifter
from lifter import resources as assets
from lifter.cli import main as cli_main
from lifter.pipeline import lift_keypoint_file
from lifter.video import lift_keypoint_sequence

KP = np.asarray(lifter.demo_sample("walking").keypoints_2d, np.float64)  # (17, 2) px, H36M order


@pytest.fixture(scope="module")
def default() -> Lifter:
    return Lifter.from_pretrained()


def file_sha(rel: str) -> str:
    return hashlib.sha256(assets.read_bytes(rel)).hexdigest()


def test_the_default_names_each_network_s_file_by_its_bytes(default):
    entry = assets.model_entry("default")
    detected = default.provenance()
    assert detected["name"] == entry["name"] and detected["poselifter_version"] == lifter.__version__
    nets = detected["networks"]
    assert [n["network"] for n in nets] == [k for k in default.networks() if k != "clean"]
    assert [n["sha256"] for n in nets] == [file_sha(entry["file"]), *map(file_sha, entry["ensemble_files"])]
    assert [n["sha256"] for n in nets] == [entry["sha256"], *entry["ensemble_sha256"]]
    clean = default.provenance(source="clean")["networks"]
    assert [n["network"] for n in clean] == ["clean"] and clean[0]["sha256"] == file_sha(entry["clean_file"])
    assert json.loads(json.dumps(detected)) == detected  # (JSON-ready as it is)


def test_the_flip_test_is_given_as_it_runs(default):
    by_default = {n["network"]: n for n in default.provenance()["networks"]}
    off = {n["network"]: n for n in default.provenance(flip_test=False)["networks"]}
    on = {n["network"]: n for n in default.provenance(flip_test=True)["networks"]}
    for key, m in default.networks().items():
        if key == "clean":
            continue
        mirror = m.config.symmetry == "mirror"
        assert by_default[key]["flip_test"] == (m.flip_test and not mirror)
        assert off[key]["flip_test"] is False and on[key]["flip_test"] is (not mirror)
        assert on[key]["symmetry"] == m.config.symmetry
    assert any(n["flip_test"] for n in by_default.values())  # (the shipped default runs it on one network)


def test_own_checkpoint_and_int8(tmp_path):
    small = tiny_lifter(32)
    assert small.weights_sha256 is None and small.provenance()["networks"][0]["sha256"] is None
    path = small.save(tmp_path / "mine.pt")
    loaded = Lifter.from_checkpoint(path)
    sha = hashlib.sha256(path.read_bytes()).hexdigest()
    assert loaded.weights_sha256 == sha
    assert loaded.provenance()["networks"] == [{"network": "detected", "sha256": sha, "flip_test": False,
                                                "symmetry": "none", "int8": False}]
    q = loaded.quantized().provenance()
    assert q["networks"][0]["int8"] is True and q["networks"][0]["sha256"] == sha
    assert loaded.networks()["detected"].weights_sha256 == sha


def test_records_carry_it_for_their_source_and_flip_test(tmp_path, default):
    f = tmp_path / "clean.json"
    f.write_text(json.dumps({"keypoints": KP.tolist(), "image_size": [1000, 1000], "focal": 1145,
                             "source": "clean"}))
    rec = lift_keypoint_file(f, lifter=default).to_dict()
    assert rec["model_info"] == default.provenance(source="clean")
    d = tmp_path / "detected.json"
    d.write_text(json.dumps({"keypoints": KP.tolist(), "image_size": [1000, 1000], "focal": 1145}))
    rec = lift_keypoint_file(d, lifter=default, flip_test=False).to_dict()
    assert rec["model_info"] == default.provenance(flip_test=False)
    # read back as a keypoint file, the field is known (no "unread field" note)
    back = tmp_path / "back.json"
    back.write_text(json.dumps(rec))
    again = lift_keypoint_file(back, lifter=default)
    assert not any("model_info" in w for w in again.warnings)
    seq = tmp_path / "seq.json"
    seq.write_text(json.dumps({"fps": 10, "image_size": [1000, 1000], "focal": 1145,
                               "frames": [{"keypoints": (KP + [3 * i, 0]).tolist()} for i in range(3)]}))
    srec = lift_keypoint_sequence(seq, lifter=default, flip_test=False).to_dict()
    assert srec["model_info"] == default.provenance(flip_test=False) != default.provenance()  # (the call's, passed on)


def test_the_cli_writes_it_for_your_own_weights(tmp_path):
    path = tiny_lifter(32).save(tmp_path / "mine.pt")
    kp = tmp_path / "pose.json"
    kp.write_text(json.dumps({"keypoints": KP.tolist(), "image_size": [1000, 1000], "focal": 1145}))
    out = tmp_path / "out"
    assert cli_main(["lift", str(kp), "--weights", str(path), "--out", str(out), "--flip-test"]) == 0
    (written,) = Path(out).glob("*.json")
    info = json.loads(written.read_text())["model_info"]
    assert info["name"] == "mine" and info["networks"] == [
        {"network": "detected", "sha256": hashlib.sha256(path.read_bytes()).hexdigest(), "flip_test": True,
         "symmetry": "none", "int8": False}]


def _copied_assets(tmp_path: Path) -> Path:
    import shutil

    src = Path(str(assets.asset("models.json"))).parent
    dst = tmp_path / "assets"
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("*.png", "demo"))
    return dst


def test_poselifter_models_lists_the_default_first_with_the_files_sha256(capsys, default):
    assert cli_main(["models", "--json"]) == 0
    listing = json.loads(capsys.readouterr().out)
    first = listing["models"][0]
    assert first["name"] == listing["default"] == default.name and first["default"] is True
    assert sorted(m["name"] for m in listing["models"]) == assets.model_names()
    shas = {n["network"]: n["sha256"] for n in first["networks"]}
    assert all(n["status"] == "ok" for m in listing["models"] for n in m["networks"])
    for source in ("detected", "clean"):  # (the same sha256 as the records' model_info)
        assert all(shas[n["network"]] == n["sha256"] for n in default.provenance(source=source)["networks"])
    assert cli_main(["models"]) == 0
    text = capsys.readouterr().out
    assert f"{default.name}  (default): 3 networks" in text and shas["clean"] in text
    assert cli_main(["models", "nope"]) == 2 and "unknown model 'nope'" in capsys.readouterr().err


def test_evaluate_json_flip_test_is_a_bool_with_each_networks_way_beside_it(default):
    """A researcher trial: the results JSON's flip_test was a bool for one network and a string for the default."""
    from lifter.cli.evaluate import flip_test_used

    name = default.name
    assert flip_test_used(default, None, "detected") == (True, f"on ({name}), built in ({name} (member 2))")
    assert flip_test_used(default, False, "detected") == (False, f"off ({name}), built in ({name} (member 2))")
    assert flip_test_used(default, None, "clean") == (True, f"on ({name} (clean 2D))")


def test_poselifter_models_says_which_training_commands_repeat_and_how_to_repeat_the_others(capsys, tmp_path):
    """A researcher trial: `poselifter models gt` printed its training command, which today trains a
    reference-camera network conditioned on `source` (the defaults changed), and `mixture`'s, which today's options
    refuse; `--config gt.pt` was refused. The paper models' stored configs are read in today's options
    (`legacy_train_config`), each command is said to repeat its network or not, and a `--config` command is given."""
    from lifter.cli.models import command_matches
    from lifter.config import TrainConfig

    gt = assets.asset("weights/gt.pt")
    cfg = TrainConfig.load(Path(gt))  # (the paper's pixel-space network on exact 2D)
    assert (cfg.model.input_space, cfg.model.conditioning, cfg.data.clean_prob, cfg.schedule.epochs) == (
        "pixel", "none", 1.0, 25.0)
    mix = TrainConfig.load(Path(assets.asset("weights/sh_mix.pt")))
    assert (mix.data.real_prob, mix.data.clean_prob, mix.augment.zoom, mix.augment.zoom_clip, mix.optim.ema_decay) == (
        0.5, 0.0, True, 1.0, 0.999)
    bp = TrainConfig.load(Path(assets.asset("weights/blazepose.pt")))
    assert bp.init == "mixture" and bp.data.error_model.endswith("blazepose_demo_train.json") and bp.optim.lr == 3e-4
    assert command_matches(assets.model_entry("gt")["train_command"], gt) == "differs"
    assert command_matches(assets.model_entry("mixture")["train_command"], assets.asset("weights/mixture.pt")) == \
        "refused"  # (--zoom-aug: renamed)
    assert command_matches(cfg_command := "poselifter train --out x.pt --input-space pixel --depth-target canonical "
                           "--conditioning none --epochs 25", gt) == "same", cfg_command
    far = assets.model_entry("universal_far")  # (trained before the EMA's warm-up: its command today has one)
    assert command_matches(far["train_command"], assets.asset(far["file"])) == "differs"
    assert command_matches(far["train_command"] + " --no-ema-warmup", assets.asset(far["file"])) == "same"
    assert TrainConfig.load(Path(assets.asset(far["file"]))).optim.ema_warmup is False
    assert command_matches("python train.py", gt) == "unknown"
    assert command_matches("poselifter train --out x.pt --config no/such.pt", gt) == "unknown"
    assert cli_main(["models", "gt"]) == 0
    out = capsys.readouterr().out
    assert "trained with (as run then; with today's options and defaults it gives another config: repeat it from " \
           "its stored config, below): poselifter train --out runs/gt_main.pt" in out
    assert f"repeat: poselifter train --config {gt} --out runs/gt_again.pt" in out
    assert "  any 2D      weights/gt.pt" in out
    assert cli_main(["models", "universal"]) == 0  # (its detected networks' stored --init is not shipped: said)
    assert "(needs its --init runs/pinhole/init_universal.pt, which is not shipped)" in capsys.readouterr().out
    # (a fine-tune's command resolves its --init's config as train does)
    ft = tmp_path / "ft.pt"
    lf = Lifter.load("universal_far")
    from lifter.checkpoint import save_checkpoint

    cfg_ft = TrainConfig.load(Path(assets.asset(far["file"])))
    from dataclasses import replace as dc_replace

    stored = dc_replace(cfg_ft, init="universal_far", optim=dc_replace(cfg_ft.optim, lr=3e-4, ema_warmup=True),
                        data=dc_replace(cfg_ft.data, error_model="sh_mixture"))
    save_checkpoint(ft, lf.net, lf.codec, train_config=stored.to_dict())
    cmd = ("poselifter train --out x.pt --init universal_far --lr 3e-4 --clean-prob 0 --real-prob 0.5 --real-rescale "
           "--noise-level-min 0.25 --noise-level-max 1.5 --ema-decay 0.999 --precision bf16 --epochs 300 "
           "--batch-size 2048 --eval-every 1000 --rotate-deg 20 --distance-prob 0.25 --lens pinhole")
    assert command_matches(cmd, ft) == "same"


@pytest.mark.parametrize("harm", ["damaged", "missing"])
def test_poselifter_models_names_a_damaged_or_missing_file(tmp_path, monkeypatch, capsys, harm):
    dst = _copied_assets(tmp_path)
    entry = assets.model_entry("default")
    f = dst / entry["ensemble_files"][0]
    if harm == "damaged":
        data = bytearray(f.read_bytes())
        data[100] ^= 0xFF
        f.write_bytes(bytes(data))
    else:
        f.unlink()
    monkeypatch.setenv("POSELIFTER_ASSETS", str(dst))
    assert cli_main(["models", "default", "gt"]) == 1
    out, err = capsys.readouterr()
    assert f"{entry['ensemble_files'][0]} is {harm}" in err and "reinstall poselifter" in err
    assert "CHECK THE FILES BELOW" in out and "gt: 1 network, 8.6 MB, files ok" in out


@pytest.mark.parametrize("flip", [True, False])
def test_photo_and_video_records_give_the_flip_test_of_the_call(tmp_path, flip):
    """A network without a mirror of its own runs the flip test exactly when the call asks: the record says which
    (a review: no photo or video record's model_info was pinned)."""
    from conftest import ScriptedEstimator

    from lifter.detect import image_from_array
    from lifter.pipeline import lift_image
    from lifter.video import lift_video

    small = tiny_lifter(32)
    H, W = 480, 640
    kp = KP * 0.5 + [100, 40]
    img = image_from_array(np.full((H, W, 3), 90, np.uint8))
    rec = lift_image(img, lifter=small, estimator=ScriptedEstimator([[kp]]), focal=600.0, flip_test=flip).to_dict()
    assert [n["flip_test"] for n in rec["model_info"]["networks"]] == [flip]
    cv2 = pytest.importorskip("cv2")
    clip = tmp_path / "clip.avi"
    vw = cv2.VideoWriter(str(clip), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (W, H))
    for i in range(3):
        vw.write(np.full((H, W, 3), 40 + 20 * i, np.uint8))
    vw.release()
    seq = lift_video(clip, lifter=small, estimator=ScriptedEstimator([[kp]] * 3), focal=600.0, flip_test=flip)
    assert seq.to_dict()["model_info"] == small.provenance(flip_test=flip)
    assert [n["flip_test"] for n in seq.to_dict()["model_info"]["networks"]] == [flip]


def test_poselifter_models_refuses_a_registry_entry_the_loader_refuses(tmp_path, monkeypatch, capsys):
    """ensemble_files without their sha256: the loader refuses the model, so the listing does not say "files ok" (a
    review: it dropped the unhashed file and said ok)."""
    dst = _copied_assets(tmp_path)
    reg = json.loads((dst / "models.json").read_text())
    reg["models"][reg["default"]]["ensemble_sha256"] = []
    (dst / "models.json").write_text(json.dumps(reg))
    monkeypatch.setenv("POSELIFTER_ASSETS", str(dst))
    with pytest.raises(lifter.PoseLifterError, match="ensemble_files and ensemble_sha256 differ"):
        Lifter.from_pretrained()
    assert cli_main(["models"]) == 1
    out, err = capsys.readouterr()
    assert "ensemble_files and ensemble_sha256 differ in length (reinstall poselifter)" in err
    assert f"{reg['default']}  (default): 0 networks, 0.0 MB, REGISTRY ENTRY DAMAGED" in out

"""Usage errors of ``poselifter evaluate`` / ``poselifter lift``: bad option values and option combinations are
rejected up front (before weights or data are loaded) with a one-line message naming the option, not a traceback."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import random_pose_cam, tiny_lifter

from lifter.camera import project
from lifter.checkpoint import save_checkpoint
from lifter.cli import main

MISSING_WEIGHTS = "no-such-dir/never.pt"
"""Weights that do not exist: a test that gets past option validation would fail with 'weights file not found'."""


def evaluate_usage_error(argv: list[str], capsys) -> str:
    """Run ``poselifter evaluate`` expecting an argparse usage error (exit 2); its stderr."""
    with pytest.raises(SystemExit) as exc:
        main(["evaluate", MISSING_WEIGHTS, *argv])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err


@pytest.mark.parametrize(
    "argv, expected",
    [
        (["--stride", "0"], "argument --stride: must be >= 1, got 0"),
        (["--stride", "-3"], "argument --stride: must be >= 1, got -3"),
        (["--stride", "x"], "argument --stride: expected an integer >= 1, got 'x'"),
        (["--max-frames-per-sequence", "0"], "argument --max-frames-per-sequence: must be >= 1, got 0"),
        (["--threads", "0"], "argument --threads: must be >= 1, got 0"),
        (["--focal-scales", "a,b"], "argument --focal-scales: expected comma-separated numbers, got 'a,b'"),
        (["--focal-scales", "1,,2"], "argument --focal-scales: expected comma-separated numbers, got '1,,2'"),
        (["--focal-scales", "0,1"], "argument --focal-scales: focal factors must be > 0, got '0,1'"),
        (["--focal-scales", "-1"], "argument --focal-scales: focal factors must be > 0"),
        (["--focal-scales", "nan,1"], "argument --focal-scales: values must be finite"),
        (["--focal-scales", "1", "--pp-shift", "5"],
         "argument --pp-shift: expected two numbers 'dx,dy' (px), got 1 value(s)"),
        (["--focal-scales", "1", "--pp-shift", "1,2,3"],
         "argument --pp-shift: expected two numbers 'dx,dy' (px), got 3"),
        (["--focal-scales", "1", "--pp-shift", "inf,0"], "argument --pp-shift: values must be finite"),
    ],
)
def test_evaluate_rejects_bad_option_values(argv, expected, capsys):
    err = evaluate_usage_error(argv, capsys)
    assert expected in err, err
    assert "poselifter evaluate: error:" in err


def test_train_rejects_bad_config_values(capsys, tmp_path):
    """Every option is a validated config field: bad values exit 2 naming the field, before any data is read."""
    for argv, expected in ((["--max-frames-per-sequence", "0"],
                            "max_frames_per_sequence must be an integer > 0, got 0"),
                           (["--train-stride", "0"], "train_stride must be an integer > 0, got 0"),
                           (["--flip-prob", "1.5"], "flip_prob must be a probability in [0, 1], got 1.5"),
                           (["--ema-decay", "1"], "ema_decay must be in [0, 1), got 1.0"),
                           (["--noise-level-min", "2", "--noise-level-max", "1"],
                            "noise_level_min 2.0 > noise_level_max")):
        assert main(["train", "--out", str(tmp_path / "m.pt"), *argv]) == 2
        assert expected in capsys.readouterr().err
    for argv, expected in ((["--epochs", "nan"], "expected a finite number"), (["--width", "x"], "expected int"),
                           (["--input-space", "rays"], "invalid choice")):
        with pytest.raises(SystemExit) as exc:
            main(["train", "--out", str(tmp_path / "m.pt"), *argv])
        assert exc.value.code == 2
        assert expected in capsys.readouterr().err


def test_train_out_must_be_a_checkpoint_name_and_not_a_file_the_run_reads(capsys, tmp_path):
    """A researcher trial: --out x.curve.json wrote a checkpoint over run x's learning curve, and --config a.pt
    --out a.pt replaced the run it was configured from; both are refused before any data is read."""
    assert main(["train", "--out", str(tmp_path / "x.curve.json")]) == 2
    assert "a checkpoint's name ends in .pt (the learning curve is written beside it as NAME.curve.json)" in (
        capsys.readouterr().err)
    from lifter.checkpoint import save_checkpoint
    from lifter.codec import PoseCodec
    from lifter.config import TrainConfig
    from lifter.model import ModelConfig, PoseLifterNet

    cfg = ModelConfig(width=16, num_blocks=1)
    run = save_checkpoint(tmp_path / "a.pt", PoseLifterNet(cfg), PoseCodec(cfg), meta={"name": "a"},
                          train_config=TrainConfig(model=cfg).to_dict())
    for option in ("--config", "--init", "--error-model"):
        assert main(["train", option, str(run), "--clean-prob", "0.5", "--out", str(tmp_path / "." / "a.pt")]) == 2
        assert f"is this run's {option}: the finished run would replace it; give another --out" in (
            capsys.readouterr().err)
    assert main(["train", "--out", str(tmp_path / "new" / "sub" / "x.json")]) == 2  # (a review: refused, and the
    assert not (tmp_path / "new").exists()  # folders were made all the same)


def test_train_says_an_error_model_that_no_sample_uses_is_not_read(capsys, tmp_path):
    """A security trial: --error-model naming a file that is not a fit was accepted without a word with every sample
    clean (the default), and failed only in a later --config repeat with noise on. A researcher trial: the name was
    still stored in the run's config; one that is no fit is now refused, naming the fix."""
    assert main(["train", "--error-model", "sh_mixture", "--print-config"]) == 0
    assert ("note: --error-model sh_mixture is not read: no sample gets synthetic noise (--clean-prob 1 "
            "+ --real-prob 0 = 1)") in capsys.readouterr().err
    assert main(["train", "--error-model", str(tmp_path / "junk.pt"), "--print-config"]) == 2
    err = capsys.readouterr().err
    assert "junk.pt" in err and "would not read it either (no sample gets synthetic noise): drop --error-model" in err
    assert main(["train", "--clean-prob", "0.5", "--print-config"]) == 0
    assert "is not read" not in capsys.readouterr().err


def test_train_init_keeps_the_networks_config_and_lens_and_refuses_options_that_ask_for_another(capsys, tmp_path):
    """A researcher trial: ``--init universal_far --input-space pixel`` dropped the option given with a vague note,
    and the fine-tune of the pinhole network trained on distorted 2D (the CLI's default lens) without a word. Now a
    model option that asks for another config than the network's is refused naming it; the network's lens is kept
    unless --lens says otherwise (then said); --print-config prints what the fine-tune runs with. No data is read."""
    lf = tiny_lifter(32)
    ck = save_checkpoint(tmp_path / "pin.pt", lf.net, lf.codec, train_config={"data": {"lens": "pinhole"}})
    assert main(["train", "--init", str(ck), "--input-space", "pixel", "--print-config"]) == 2
    err = capsys.readouterr().err
    assert (f"--init {ck}: a fine-tune keeps the network's model config, and --input-space 'pixel' (the network's: "
            "'camera') asks for another; drop that option, or train a new network without --init") in err, err
    assert main(["train", "--init", str(ck), "--width", "64", "--dropout", "0.1", "--print-config"]) == 2
    assert "--width 64 (the network's: 32), --dropout 0.1" in capsys.readouterr().err
    assert main(["train", "--init", str(ck), "--width", "32", "--print-config"]) == 0  # (the network's own: fine)
    got = capsys.readouterr()
    cfg = json.loads(got.out)
    assert cfg["data"]["lens"] == "pinhole" and cfg["model"] == lf.net.config.to_dict()
    assert f"--init {ck} learned 'pinhole' 2D: training on it too (--lens pinhole" in got.err, got.err
    assert main(["train", "--init", str(ck), "--lens", "h36m", "--print-config"]) == 0
    got = capsys.readouterr()
    assert json.loads(got.out)["data"]["lens"] == "h36m"
    assert f"--init {ck} learned 'pinhole' 2D, and this run trains it on 'h36m' (--lens)" in got.err, got.err
    # a stored fine-tune whose --init is not here still prints its config, said (a review: `universal` stores an
    # --init that is not shipped, and printing its config failed)
    from lifter.config import TrainConfig

    ft = save_checkpoint(tmp_path / "ft.pt", lf.net, lf.codec,
                         train_config={**TrainConfig().to_dict(), "init": "no/such/start.pt"})
    assert main(["train", "--config", str(ft), "--print-config"]) == 0
    got = capsys.readouterr()
    assert json.loads(got.out)["init"] == "no/such/start.pt"
    assert "weights file not found: no/such/start.pt" in got.err and "the config is printed as stored" in got.err
    assert main(["train", "--config", str(ft), "--out", str(tmp_path / "x.pt")]) == 2  # (training needs it)
    assert "weights file not found" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv, expected",
    [
        (["--focal-scales", "1,2", "--inputs", "sh"],
         "--focal-scales cannot be combined with --inputs sh: the focal sweep re-projects the ground-truth 3D poses"),
        (["--focal-scales", "1,2", "--analytic-root"], "--analytic-root cannot be combined with --focal-scales"),
        (["--focal-scales", "1,2", "--per-action"], "--per-action cannot be combined with --focal-scales"),
        (["--focal-scales", "1,2", "--pck-plot", "x.png"], "--pck-plot cannot be combined with --focal-scales"),
        (["--focal-scales", "1", "--analytic-root", "--per-action"],
         "--analytic-root, --per-action cannot be combined with --focal-scales"),
        (["--pp-shift", "10,0"], "--pp-shift only applies to the virtual cameras of --focal-scales"),
        # (a user trial: PNG data was written under the .jpg name)
        (["--pck-plot", "x.jpg"], "--pck-plot: x.jpg is not a name a plot can be written under: name it .png, .pdf "
                                  "or .svg"),
    ],
)
def test_evaluate_rejects_ignored_option_combinations(argv, expected, capsys):
    """These used to be silently ignored (or, for --inputs sh, the detections silently replaced by GT 2D)."""
    code = main(["evaluate", MISSING_WEIGHTS, *argv])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("poselifter evaluate: error: "), err
    assert expected in err, err
    assert "not found" not in err  # rejected before the weights are loaded


def test_evaluate_valid_sweep_options_pass_validation(capsys):
    """Good values parse (and then fail only on the missing weights, i.e. after validation)."""
    code = main(["evaluate", MISSING_WEIGHTS, "--focal-scales", " 0.5, 1,2 ", "--pp-shift", "100,-80", "--stride", "50",
                 "--max-frames-per-sequence", "1"])
    err = capsys.readouterr().err
    assert code == 2
    assert "weights file not found" in err, err


# ------------------------------------------------------------------------------------------------
# poselifter lift
# ------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def weights(tmp_path_factory) -> Path:
    return _save_tiny(tmp_path_factory.mktemp("w") / "tiny.pt", 16)


@pytest.fixture()
def kp_file(tmp_path) -> Path:
    kp = project(random_pose_cam(np.random.default_rng(0), 1)[0], focal=1000.0, principal_point=(640.0, 360.0))
    path = tmp_path / "pose.json"
    path.write_text(json.dumps({"keypoints": kp.tolist(), "image_size": [1280, 720]}))
    return path


def lift(argv: list[str], capsys) -> tuple[int, str]:
    code = main(["lift", "--no-progress", *argv])
    return code, capsys.readouterr().err


def test_lift_out_is_an_existing_file(tmp_path, weights, kp_file, capsys):
    afile = tmp_path / "afile"
    afile.write_text("keep me")
    code, err = lift([str(kp_file), "--out", str(afile), "--weights", str(weights)], capsys)
    assert code == 2
    assert err.strip() == (f"poselifter lift: error: --out {afile}: exists and is not a folder; --out names the "
                           "output folder")
    assert afile.read_text() == "keep me"
    # a folder below a regular file cannot be created either
    code, err = lift([str(kp_file), "--out", str(afile / "sub"), "--weights", str(weights)], capsys)
    assert code == 2
    assert f"--out {afile / 'sub'}: cannot create the output folder" in err
    assert "Traceback" not in err


@pytest.mark.parametrize(
    "argv, expected",
    [
        (["--focal", "1e30"], "--focal must be a number or [fx, fy] in px, each in (0, 1e+06), got [1e+30, 1e+30]"),
        (["--focal", "1000", "0"], "--focal must be a number or [fx, fy] in px, each in (0, 1e+06), got [1000.0, 0.0]"),
        # (once, before any input: it was refused per input, with a message naming focal=None)
        (["--focal", "4.2"], "--focal 4.2 px is too small (< 10 px): give the focal length in pixels, not mm"),
        (["--focal", "1", "2", "3"], "--focal takes FX or FX FY, got 3 values"),
        (["--principal-point", "nan", "3"], "--principal-point must be [cx, cy] in px, each finite"),
        (["--principal-point", "5e7", "3"], "--principal-point must be [cx, cy] in px"),
        (["--fov", "0"], "--fov must be a diagonal field of view in [1, 150] degrees (a long telephoto to beyond "
                         "the widest phone lens, ~120), got 0"),
        (["--fov", "179"], "--fov must be a diagonal field of view in [1, 150] degrees"),  # (user trial: 179 passed,
        # then failed on a focal length 'in mm' the user never gave)
        (["--sensor-width", "0"], "--sensor-width must be the sensor's long side in mm, in (0, 1000), got 0"),
        (["--max-side", "0"], "--max-side must be a whole number of px >= 256"),
        (["--max-side", "10"], "--max-side must be a whole number of px >= 256"),
        (["--max-people", "0"], "--max-people must be >= 1, got 0"),
        (["--detector", "foo"], "--detector 'foo': unknown 2D estimator; available: ["),
    ],
)
def test_lift_rejects_bad_global_options_up_front(tmp_path, weights, kp_file, argv, expected, capsys):
    out = tmp_path / "out"
    code, err = lift([str(kp_file), "--out", str(out), "--weights", str(weights), *argv], capsys)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"poselifter lift: error: {expected}"), err
    assert not out.exists()  # nothing processed



def test_an_assumed_focal_below_the_limit_names_fov_not_a_focal_in_mm(tmp_path, weights, capsys):
    """A tiny image at a wide --fov assumes a focal length under 10 px: the message names the assumption and the
    options, not the lifter's 'focal length in mm' advice for a focal the user never gave."""
    p = tmp_path / "tiny.json"
    p.write_text(json.dumps({"keypoints": [[10 + i, 5 + i] for i in range(17)], "image_size": [40, 30]}))
    code, err = lift([str(p), "--out", str(tmp_path / "out"), "--weights", str(weights), "--fov", "150"], capsys)
    assert code == 1
    assert "the focal length assumed for this 40 x 30 px image (no focal length given: assumed a 150 deg diagonal " \
           "field of view -> 6.7 px) is 6.7 px, below 10 px: give the focal length with focal= (--focal), or a " \
           "narrower field of view with fov_deg= (--fov)" in err, err
    assert "not mm" not in err and "focal=None" not in err

@pytest.mark.parametrize(
    "fields, expected",
    [
        ({"image_size": "1000x1000"},
         "image_size must be a list [width, height] in px (whole numbers in [1, 100000]), got '1000x1000'"),
        ({"image_size": [1000]}, ("image_size needs two values [width, height] in px (whole numbers in [1, 100000]), "
                                  "got 1: [1000]")),
        ({"image_size": [1000, 1000, 3]}, "image_size needs two values [width, height]"),
        ({"image_size": ["1000", "1000"]}, "image_size must be numbers [width, height]"),
        ({"image_size": [1e30, 1000]}, ("image_size must be [width, height] in px (whole numbers in [1, 100000]), "
                                        "got [1e+30, 1000]")),
        ({"image_size": [0, 1000]}, "image_size must be [width, height] in px"),
        ({"image_size": [640.5, 480]}, "image_size must be [width, height] in px (whole numbers"),
        ({"focal": 1e30}, "focal must be a number or [fx, fy] in px, each in (0, 1e+06), got [1e+30, 1e+30]"),
        ({"focal": [1000, -5]}, "focal must be a number or [fx, fy] in px, each in (0, 1e+06), got [1000.0, -5.0]"),
        ({"focal": [1000, 1000, 1000]}, "focal must be a number or [fx, fy] in px"),
        ({"focal": "wide"}, "focal must be a number or [fx, fy] in px, each in (0, 1e+06), got 'wide'"),
        ({"principal_point": [1e30, 0]},
         "principal_point must be [cx, cy] in px, each finite with magnitude below 1e+06"),
        ({"principal_point": [640]}, "principal_point must be [cx, cy] in px"),
    ],
)
def test_lift_rejects_bad_camera_fields_in_keypoint_files(tmp_path, weights, kp_file, fields, expected, capsys):
    doc = json.loads(kp_file.read_text())
    doc.update(fields)
    kp_file.write_text(json.dumps(doc))
    out = tmp_path / "out"
    code, err = lift([str(kp_file), "--out", str(out), "--weights", str(weights)], capsys)
    assert code == 1, err
    assert f"error: {kp_file}: {expected}" in err, err
    assert not (out / "pose.json").exists()


def test_lift_huge_image_size_with_explicit_camera_writes_no_nan(tmp_path, weights, kp_file, capsys):
    """With --focal and --principal-point the absurd image size used to pass and end up in the output."""
    doc = json.loads(kp_file.read_text())
    doc["image_size"] = [1e30, 1000]
    kp_file.write_text(json.dumps(doc))
    out = tmp_path / "out"
    code, err = lift([str(kp_file), "--out", str(out), "--weights", str(weights), "--focal", "1000",
                      "--principal-point", "640", "360"], capsys)
    assert code == 1
    assert "image_size must be [width, height]" in err
    assert not (out / "pose.json").exists()


def test_lift_good_camera_fields_still_work(tmp_path, weights, kp_file, capsys):
    doc = json.loads(kp_file.read_text())
    doc.update({"image_size": [1280.0, 720], "focal": [1000, 1001.5], "principal_point": [640, 360.5]})
    kp_file.write_text(json.dumps(doc))
    out = tmp_path / "out"
    code, err = lift([str(kp_file), "--out", str(out), "--weights", str(weights)], capsys)
    assert code == 0, err
    res = json.loads((out / "pose.json").read_text())
    assert res["image_size"] == [1280, 720]
    assert res["focal"] == [1000.0, 1001.5] and res["principal_point"] == [640.0, 360.5]
    assert np.all(np.isfinite(res["absolute"]))


def _save_tiny(path, width: int):
    lf = tiny_lifter(width)
    return save_checkpoint(path, lf.net, lf.codec)


def test_output_into_a_closed_pipe_is_not_a_traceback():
    """``poselifter train --print-config | head -1`` ended in a BrokenPipeError traceback (a helper's trial): a
    reader that closed the pipe now ends the command quietly with the shell's status for it (141)."""
    import subprocess
    import sys

    p = subprocess.Popen([sys.executable, "-m", "lifter", "train", "--print-config"], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE)
    assert p.stdout is not None and p.stderr is not None
    p.stdout.close()  # (the reader is gone before the first write)
    err = p.stderr.read().decode()
    assert p.wait(timeout=120) == 141 and "Traceback" not in err and "BrokenPipeError" not in err, err


def test_h36m_help_names_the_folder_it_reads(capsys, monkeypatch):
    """A researcher's trial read "default ../shared/data/h36m" as relative to the working folder; in a source
    checkout it is beside the project. The help names the resolved folder, or $POSELIFTER_H36M's when set."""
    from lifter.data import DEFAULT_H36M_DIR

    monkeypatch.delenv("POSELIFTER_H36M", raising=False)
    for command in ("evaluate", "train", "fit-noise"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        out = "".join(capsys.readouterr().out.split())  # (argparse wraps long paths anywhere)
        want = "".join(f"(default: {DEFAULT_H36M_DIR.resolve()}, or $POSELIFTER_H36M when set)".split())
        assert want in out, (command, out)
    monkeypatch.setenv("POSELIFTER_H36M", "/somewhere/h36m")
    with pytest.raises(SystemExit):
        main(["evaluate", "--help"])
    assert "(default:$POSELIFTER_H36M,/somewhere/h36m)" in "".join(capsys.readouterr().out.split())


@pytest.mark.parametrize("suffix", ["png", "pdf", "svg"])
def test_a_plot_is_written_in_the_format_its_name_says(tmp_path, suffix):
    """lifter.plots writes each plot in the format of its suffix (it wrote PNG data under any name)."""
    from lifter import PoseLifterError
    from lifter.plots import plot_pck_curves

    out = plot_pck_curves({"a": (np.linspace(0, 150, 31), np.linspace(0, 1, 31))}, tmp_path / f"p.{suffix}")
    head = out.read_bytes()[:64]
    assert {"png": head.startswith(b"\x89PNG"), "pdf": head.startswith(b"%PDF"), "svg": b"<?xml" in head}[suffix]
    with pytest.raises(PoseLifterError, match=r"the plot: p.jpg is not a name a plot can be written under"):
        plot_pck_curves({"a": (np.linspace(0, 150, 31), np.linspace(0, 1, 31))}, tmp_path / "p.jpg")
    assert not (tmp_path / "p.jpg").exists()


def test_commands_print_the_lifters_warnings_as_note_lines(monkeypatch, capsys):
    """A researcher trial: a warning read ``.venv/bin/poselifter:6: PoseLifterWarning: ... sys.exit(main())``. Every
    command prints a PoseLifterWarning as a ``note:`` line, as evaluate did."""
    import warnings

    import lifter.cli.models as models
    from lifter._checks import PoseLifterWarning, warn_user

    monkeypatch.setattr(models, "run_models", lambda args: warn_user("something to say") or 0)
    with warnings.catch_warnings():
        warnings.simplefilter("always", PoseLifterWarning)  # (shown, whatever the test run's own filter)
        assert main(["models"]) == 0
    err = capsys.readouterr().err
    assert err == "note: something to say\n"
    # (a review: any other warning ended the command with a TypeError, showwarning being called with 6 arguments)
    monkeypatch.setattr(models, "run_models",
                        lambda args: warnings.warn("numpy says", RuntimeWarning, stacklevel=1) or 0)
    with warnings.catch_warnings():
        warnings.simplefilter("always", RuntimeWarning)
        assert main(["models"]) == 0
    assert "RuntimeWarning: numpy says" in capsys.readouterr().err


def test_evaluate_refuses_two_rows_of_one_label(capsys):
    """A researcher trial: ``x=runs/a.pt x=runs/b.pt`` printed two rows "x" whose JSON objects could not be told
    apart (and one's provenance was lost, kept by label); refused before any weights are read."""
    assert main(["evaluate", "x=runs/none_a.pt", "x=runs/none_b.pt"]) == 2
    assert ("two models are labelled 'x': give each row its own label (LABEL=MODEL, e.g. a=runs/none_a.pt "
            "b=runs/none_b.pt)") in capsys.readouterr().err


def test_a_value_starting_with_a_minus_sign_is_read_as_the_options_value(capsys):
    """argparse takes '-1' for a number but '-100,80' for an option ("expected one argument", a researcher trial's
    --focal-scales -1,1): an option that takes one value is given it, and the value is then checked by name."""
    from lifter.cli import _parse, build_parser

    args = _parse(build_parser("evaluate"), ["evaluate", "--pp-shift", "-100,80", "--focal-scales", "0.5,1"])
    assert tuple(args.pp_shift) == (-100.0, 80.0) and list(args.focal_scales) == [0.5, 1.0]
    with pytest.raises(SystemExit):
        main(["evaluate", "--focal-scales", "-1,1"])
    assert "argument --focal-scales: focal factors must be > 0, got '-1,1'" in capsys.readouterr().err
    # '--opt=-5,5' as typed and an abbreviation work; nothing after '--' is touched (a review: two inputs became one)
    args = _parse(build_parser("evaluate"), ["evaluate", "--pp-shift=-5,5"])
    assert tuple(args.pp_shift) == (-5.0, 5.0)
    args = _parse(build_parser("evaluate"), ["evaluate", "--pp", "-5,5"])
    assert tuple(args.pp_shift) == (-5.0, 5.0)
    args = _parse(build_parser("lift"), ["lift", "-o", "out", "--", "--out", "-1.json"])
    assert list(args.inputs) == ["--out", "-1.json"]

"""The Python module against the CLI, on whatever Vulkan adapter is present (lavapipe in CI).

Images are small (32 x 24) with few frames: lavapipe renders on the CPU. `cargo xtask test`
builds the module and runs this suite with LIGHTGRAPH_BIN naming the CLI binary of the same
build; without it the CLI's commands run in-process through `lightgraph.cli`.
"""

import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

import lightgraph

REPO = Path(__file__).resolve().parents[2]
RES = (32, 24)


def run_cli(args):
    """Runs `lightgraph ARGS` as the CLI binary when LIGHTGRAPH_BIN names one."""
    binary = os.environ.get("LIGHTGRAPH_BIN")
    if binary:
        subprocess.run([binary, *args], check=True, cwd=REPO, capture_output=True)
    else:
        lightgraph.cli(args)


def check_image(image):
    assert image.shape == (RES[1], RES[0], 3)
    assert image.dtype == np.float32
    assert np.isfinite(image).all()
    assert image.mean() > 0.0, "a lit Cornell box renders black"


def test_the_default_scene_renders_as_the_cli_renders_it(tmp_path):
    image, stats = lightgraph.render(res=RES, frames=8, seed=5)
    check_image(image)
    assert stats["frames"] == 8 and stats["samples"] == 8 and stats["rays"] > 0
    out = tmp_path / "cli.exr"
    run_cli(["render", "--res", "32x24", "--frames", "8", "--seed", "5", "--out", str(out)])
    cli_image, info = lightgraph.read(out)
    assert info["seed"] == "5" and info["samples"] == 8
    # Same seed, frames and device: the same estimate. The CLI's film keeps f64 sums of the
    # same f32 frames, so they agree to float rounding, far below the noise of 8 samples.
    np.testing.assert_allclose(image, cli_image, rtol=1e-5, atol=1e-6)
    assert abs(image.mean() - cli_image.mean()) <= 1e-5 * cli_image.mean()


@pytest.mark.parametrize(
    "scene",
    ["scenes/cornell/cornell-diffuse.ron", "tests/data/mitsuba/version-0.5.xml"],
)
def test_a_scene_file_renders_as_the_cli_renders_it(tmp_path, scene):
    path = str(REPO / scene)
    image, _ = lightgraph.render(scene=path, res=RES, frames=4, seed=2)
    check_image(image)
    out = tmp_path / "cli.exr"
    run_cli(["render", "--scene", path, "--res", "32x24", "--frames", "4", "--seed", "2", "--out", str(out)])
    cli_image, _ = lightgraph.read(out)
    np.testing.assert_allclose(image, cli_image, rtol=1e-5, atol=1e-6)


def test_a_bad_scene_raises_the_clis_message_with_file_line_and_column(tmp_path):
    bad = tmp_path / "bad.ron"
    bad.write_text("Scene(\n    camera: (position: (0, 0, 0),,\n)\n")
    with pytest.raises(lightgraph.Error) as e:
        lightgraph.render(scene=str(bad), res=RES, frames=1)
    assert re.search(r"bad\.ron:2:\d+", str(e.value)), str(e.value)


def test_bad_options_raise_errors_not_crashes():
    with pytest.raises(lightgraph.Error, match="no-such-graph"):
        lightgraph.render(graph="no-such-graph", res=RES, frames=1)
    with pytest.raises(lightgraph.Error, match="NOT_A_CONSTANT|not a valid value"):
        lightgraph.render(res=RES, frames=1, constants={"MAX_PATH_LENGTH": "many"})


def rmse(a, b):
    return float(np.sqrt(np.mean((a.astype(np.float64) - b) ** 2)))


def test_a_session_loops_and_its_error_falls_with_frames(tmp_path):
    ref = lightgraph.reference(scene="cornell-diffuse", out=tmp_path / "ref.exr", res=RES, frames=256)
    assert ref.shape == (RES[1], RES[0], 3)
    session = lightgraph.Session(scene="cornell-diffuse", res=RES, seed=1)
    errors = {}
    while session.frames < 64:
        session.render(frames=max(session.frames, 1))
        errors[session.frames] = rmse(session.image(), ref)
    assert list(errors) == [1, 2, 4, 8, 16, 32, 64]
    assert session.stats()["samples"] == 64
    # The error is sqrt(s^2 / n + s^2 / 256) for n frames against a 256-frame reference:
    # from 4 to 64 frames it falls by sqrt((1/4 + 1/256) / (1/64 + 1/256)) = 3.6. Asking for
    # a factor 2 leaves room for the noise of an RMSE over 768 pixels (a few per cent).
    assert errors[64] < errors[4] / 2, errors
    assert errors[64] < errors[16] < errors[4], errors


def test_compare_explain_and_list(tmp_path):
    lightgraph.reference(scene="cornell-diffuse", out=tmp_path / "ref.exr", res=RES, frames=16)
    summary = lightgraph.compare(
        tmp_path / "ref.exr", "pt:NaivePTsk,pt:NaivePTmk", time=1.0, out=tmp_path / "cmp"
    )
    assert "NaivePTsk" in summary and "NaivePTmk" in summary
    assert (tmp_path / "cmp" / "curves.csv").exists()
    text = lightgraph.explain(graph="pt", layout="NaivePTmk", res=RES)
    assert "NaivePTmk" in text and "kernel" in text
    listed = lightgraph.list()
    assert "pt" in listed["graphs"] and "cornell-mitsuba" in listed["scenes"]
    assert listed["adapters"], "no adapter listed, yet the renders ran"


def test_a_study_sums_up_its_scenes(tmp_path):
    summary = lightgraph.study(
        ["cornell-diffuse"],
        estimators=["pt:NaivePTsk", "pt:NaivePTmk"],
        time=1.0,
        reference_time=2.0,
        reference_graph="pt",
        res=RES,
        out=tmp_path / "study",
    )
    assert "cornell-diffuse" in summary and "NaivePTmk" in summary
    rows = (tmp_path / "study" / "summary.csv").read_text().splitlines()
    assert len(rows) == 3, rows  # the header and one row per estimator
    assert (tmp_path / "study" / "references" / "cornell-diffuse.exr").exists()
    with pytest.raises(lightgraph.Error, match="no-such-scene"):
        lightgraph.study(["no-such-scene"], out=tmp_path / "bad")

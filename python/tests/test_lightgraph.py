"""The Python module against the CLI, on whatever Vulkan adapter is present (lavapipe in CI).

Images are small (32 x 24) with few frames: lavapipe renders on the CPU. `cargo xtask test`
builds the module and runs this suite with LIGHTGRAPH_BIN naming the CLI binary of the same
build; without it the CLI's commands run in-process through `lightgraph.cli`.
"""

import inspect
import os
import re
import subprocess
import sys
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


def refused(call, message):
    """`call` raises ValueError matching `message`, in Python's words, not the CLI's."""
    with pytest.raises(ValueError, match=message) as e:
        call()
    text = str(e.value)
    assert "--" not in text and "try '--help'" not in text and "\n" not in text, text


def test_bad_values_raise_value_errors_naming_the_keyword(tmp_path):
    cases = [
        (lambda: lightgraph.render(frames=-1), r"^frames=-1: it must be at least 1"),
        (lambda: lightgraph.render(frames=0), r"^frames=0: "),
        (lambda: lightgraph.render(res=(0, 0)), r"^res=\(0, 0\): width and height: "),
        (lambda: lightgraph.render(res=RES, time=-1.0), r"^time=-1.0: .*above zero"),
        (lambda: lightgraph.render(res=RES, time=0.0), r"^time=0.0: "),
        (lambda: lightgraph.render(spp=0), r"^spp=0: "),
        (lambda: lightgraph.render(seed=-1), r"^seed=-1: it must be from 0 to 4294967295"),
        (lambda: lightgraph.render(max_path_length=0), r"^max_path_length=0: "),
        (lambda: lightgraph.Session(res=(-3, 4)), r"^res=\(-3, 4\): "),
        (lambda: lightgraph.reference(out=tmp_path / "r.exr", frames=0), r"^frames=0: "),
        (lambda: lightgraph.compare(tmp_path / "r.exr", "pt", time=0.0), r"^time=0.0: "),
        (lambda: lightgraph.compare(tmp_path / "r.exr", "pt", per_decade=0), r"^per_decade=0: "),
        (lambda: lightgraph.study(["cornell-diffuse"], reference_time=-2.0), r"^reference_time=-2.0: "),
        (lambda: lightgraph.explain(spp=0), r"^spp=0: "),
    ]
    for call, message in cases:
        refused(call, message)
    assert not (tmp_path / "r.exr").exists()
    session = lightgraph.Session(res=RES)
    refused(lambda: session.render(frames=0), r"^frames=0: ")
    refused(lambda: session.render(time=float("nan")), r"^time=nan: ")
    assert session.frames == 0


def test_sizes_that_cannot_fit_are_refused_before_any_work():
    refused(lambda: lightgraph.render(res=(100000, 100000)), r"^res=\(100000, 100000\) with spp=1: 10000000000 paths")
    refused(lambda: lightgraph.render(res=(256, 256), spp=100000), r"with spp=100000: 6553600000 paths")


def test_unknown_constants_and_values_of_the_wrong_type_are_refused():
    refused(
        lambda: lightgraph.render(res=RES, constants={"NO_SUCH": 1}),
        r"^constants\['NO_SUCH'\]: graph pt has no constant NO_SUCH; its constants: .*MAX_PATH_LENGTH",
    )
    refused(
        lambda: lightgraph.render(graph="ppm", res=RES, constants={"PM_RADUIS": 0.5}),
        r"graph ppm has no constant PM_RADUIS; close names: PM_RADIUS",
    )
    refused(
        lambda: lightgraph.render(res=RES, constants={"MAX_PATH_LENGTH": "many"}),
        r"^constants\['MAX_PATH_LENGTH'\]: MAX_PATH_LENGTH is a u32 .*'many'",
    )
    refused(
        lambda: lightgraph.explain(graph="vcm", constants={"VCM_MERGE": 2}),
        r"VCM_MERGE is a bool",
    )


def test_every_parameter_is_documented():
    for function in [lightgraph.Session, lightgraph.Session.render, lightgraph.render, lightgraph.reference,
                     lightgraph.compare, lightgraph.study, lightgraph.explain, lightgraph.read, lightgraph.cli]:
        doc = function.__doc__ or ""
        names = [n for n in inspect.signature(function).parameters if n != "self"]
        assert names, function
        for name in names:
            assert f"- {name}:" in doc, f"{function.__name__} does not document {name}: {doc}"


def test_importing_and_listing_print_nothing():
    env = {k: v for k, v in os.environ.items() if k != "XDG_RUNTIME_DIR"}
    code = "import lightgraph; lightgraph.list()"
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert done.stderr == "" and done.stdout == "", done.stderr


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

"""The Python module against the CLI, on whatever Vulkan adapter is present (lavapipe in CI).

Images are small (32 x 24) with few frames: lavapipe renders on the CPU. `cargo xtask test`
builds the module and runs this suite with LIGHTGRAPH_BIN naming the CLI binary of the same
build; without it the CLI's commands run in-process through `lightgraph.cli`.
"""

import base64
import csv
import inspect
import json
from html import unescape
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
                     lightgraph.compare, lightgraph.study, lightgraph.verify, lightgraph.explain, lightgraph.read,
                     lightgraph.cli, lightgraph.to_png]:
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


def as_columns(table):
    """A table `compare`, `study` or `verify` returns (DataFrame or dict of arrays) as a dict of lists."""
    return {name: list(table[name]) for name in table}


def csv_columns(path):
    """The CSV file at `path` read by Python's csv module, as a dict of lists of text."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {name: [row[i] for row in rows[1:]] for i, name in enumerate(rows[0])}


def check_table(table, path):
    """`table` holds the CSV file at `path`: its columns in order, numbers as float64 arrays."""
    pandas = sys.modules.get("pandas")
    if pandas is not None:
        assert isinstance(table, pandas.DataFrame), type(table)
    else:
        assert isinstance(table, dict) and all(isinstance(v, np.ndarray) for v in table.values()), table
    expected = csv_columns(path)
    got = as_columns(table)
    assert list(got) == list(expected)
    for name, texts in expected.items():
        values = got[name]
        assert len(values) == len(texts), name
        if np.asarray(table[name]).dtype == np.float64:
            numbers = [float(t) if t else float("nan") for t in texts]
            np.testing.assert_array_equal(np.asarray(values, dtype=np.float64), numbers, err_msg=name)
        else:
            assert [str(v) for v in values] == texts, name


def test_compare_returns_its_tables_and_images(tmp_path):
    ref = tmp_path / "ref.exr"
    lightgraph.reference(scene="cornell-diffuse", out=ref, res=RES, frames=16)
    found = lightgraph.compare(ref, "pt:NaivePTsk,pt:NaivePTmk", time=1.0, out=tmp_path / "cmp")
    assert "NaivePTsk" in found["summary"] and "NaivePTmk" in found["summary"]
    assert found["summary"] == (tmp_path / "cmp" / "summary.md").read_text()
    check_table(found["curves"], tmp_path / "cmp" / "curves.csv")
    assert set(found["curves"]["run"]) == {"pt:NaivePTsk", "pt:NaivePTmk"}
    assert sorted(found["images"]) == ["pt:NaivePTmk", "pt:NaivePTsk"]
    for image in found["images"].values():
        check_image(image)
    np.testing.assert_array_equal(found["reference"], lightgraph.read(ref)[0])


def test_reference_frames_with_resume_are_the_films_total(tmp_path):
    ref = tmp_path / "ref.exr"
    lightgraph.reference(scene="cornell-diffuse", out=ref, res=(16, 16), frames=4)
    lightgraph.reference(scene="cornell-diffuse", resume=ref, out=ref, frames=6)
    # 6 in all, as the CLI's --frames counts them with --resume (not 6 more).
    assert lightgraph.read(ref)[1]["frames"] == 6
    written = ref.stat().st_mtime_ns
    with pytest.raises(ValueError, match=r"ref\.exr: the film holds 6 frames already, and frames=6 asks for 6 in all"):
        lightgraph.reference(scene="cornell-diffuse", resume=ref, out=ref, frames=6)
    # Refused before any work: the film is as it was.
    assert ref.stat().st_mtime_ns == written and lightgraph.read(ref)[1]["frames"] == 6


def test_explain_and_list():
    text = lightgraph.explain(graph="pt", layout="NaivePTmk", res=RES)
    assert "NaivePTmk" in text and "kernel" in text
    listed = lightgraph.list()
    assert "pt" in listed["graphs"] and "cornell-mitsuba" in listed["scenes"]
    assert listed["adapters"], "no adapter listed, yet the renders ran"


def test_a_study_returns_its_tables_and_images(tmp_path):
    found = lightgraph.study(
        ["cornell-diffuse"],
        estimators=["pt:NaivePTsk", "pt:NaivePTmk"],
        time=1.0,
        reference_time=2.0,
        reference_graph="pt",
        res=RES,
        out=tmp_path / "study",
    )
    assert "cornell-diffuse" in found["summary"] and "NaivePTmk" in found["summary"]
    rows = (tmp_path / "study" / "summary.csv").read_text().splitlines()
    assert len(rows) == 3, rows  # the header and one row per estimator
    check_table(found["table"], tmp_path / "study" / "summary.csv")
    check_table(found["layouts"], tmp_path / "study" / "layouts.csv")
    scene = found["scenes"]["cornell-diffuse"]
    check_table(scene["curves"], tmp_path / "study" / "cornell-diffuse" / "curves.csv")
    assert sorted(scene["images"]) == ["pt:NaivePTmk", "pt:NaivePTsk"]
    check_image(scene["reference"])
    reference = tmp_path / "study" / "references" / "cornell-diffuse.exr"
    np.testing.assert_array_equal(scene["reference"], lightgraph.read(reference)[0])
    with pytest.raises(lightgraph.Error, match="no-such-scene"):
        lightgraph.study(["no-such-scene"], out=tmp_path / "bad")


def verify_pt_layouts(out, **options):
    """`verify` of path tracing's two layouts on the diffuse box, 8 frames in 4 batches."""
    return lightgraph.verify(
        scenes=["cornell-diffuse"],
        graphs=["pt:NaivePTsk", "pt:NaivePTmk"],
        frames=8,
        batches=4,
        out=out,
        **options,
    )


def test_verify_returns_its_table_and_images(tmp_path):
    out = tmp_path / "verify"
    found = verify_pt_layouts(out, block=8, res=RES)
    # 8 frames cannot decide the pair: the command's failure comes with the tables.
    assert "could not be decided" in found["failed"], found["failed"]
    assert found["summary"] == (out / "verify.md").read_text()
    check_table(found["table"], out / "verify.csv")
    assert list(found["table"]["verdict"]) == csv_columns(out / "verify.csv")["verdict"]
    assert len(found["table"]["verdict"]) == 1  # one pair
    images = found["scenes"]["cornell-diffuse"]["images"]
    assert sorted(images) == ["pt:NaivePTmk", "pt:NaivePTsk"]
    for image in images.values():
        check_image(image)
    refused(lambda: lightgraph.verify(batches=1, out=out), r"^batches=1: it must be at least 2")
    with pytest.raises(lightgraph.Error, match="no-such-scene"):
        lightgraph.verify(scenes=["no-such-scene"], graphs=["pt"], frames=8, res=RES, out=out)


def test_verify_takes_a_preset_and_what_is_given_wins(tmp_path):
    out = tmp_path / "verify"
    found = verify_pt_layouts(out, block=16, preset="lavapipe")
    # The preset's size (32 x 32) and power; the blocks of 16 given: 4 of them.
    for image in found["scenes"]["cornell-diffuse"]["images"].values():
        assert image.shape == (32, 32, 3)
    assert "a 7.0% difference of the image mean and a 25% difference in the blocks holding 75%" in found["summary"]
    assert list(found["table"]["blocks"]) == [4]
    assert "| cornell-diffuse | pt:NaivePTsk | 8 |" in found["summary"], found["summary"]
    refused(lambda: lightgraph.verify(preset="GPU", out=out), r"^preset='GPU': it must be one of 'lavapipe', 'gpu'$")


def png_size(data):
    """Width and height of a PNG file's bytes."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", data[:8]
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def test_a_session_shows_itself_in_jupyter():
    session = lightgraph.Session(scene="cornell-diffuse", res=RES)
    session.render(frames=2)
    data = session._repr_png_()
    assert png_size(data) == RES
    html = session._repr_html_()
    frame = re.fullmatch(r'<iframe srcdoc="([^"]*)" style="[^"]*"></iframe>', html)
    assert frame, html[:300]
    page = unescape(frame.group(1))
    assert "<script" in page and "2 frames" in page, page[:300]
    # The viewer's page holds the image's float data (base64 of little-endian f32 RGB).
    pixels = session.image().astype("<f4").tobytes()
    assert base64.b64encode(pixels[:3000]).decode() in page
    # The PNG is the CLI's preview of the same image: sRGB in 8 bits.
    assert lightgraph.to_png(session.image()) == data
    refused(lambda: lightgraph.to_png(np.zeros((4, 4, 2), np.float32)), r"^image of shape \[4, 4, 2\]: ")


INTERRUPTED = """
import json, os, signal, sys, threading, time
import lightgraph

def ctrl_c_in(seconds):
    threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT)).start()

found = {}
# The process's first render (the numpy capsule's first use once panicked at Ctrl-C).
ctrl_c_in(5.0)
try:
    lightgraph.render(scene="cornell-diffuse", res=(16, 16), frames=10**9)
    found["render"] = "finished"
except KeyboardInterrupt as e:
    found["render"] = {"frames": e.stats["frames"], "shape": list(e.image.shape),
                       "finite": bool(e.image.sum() >= 0), "message": str(e)}

session = lightgraph.Session(scene="cornell-diffuse", res=(16, 16))
session.render(frames=2)
ctrl_c_in(1.0)
started = time.monotonic()
try:
    session.render(frames=10**9)
    found["session"] = "finished"
except KeyboardInterrupt as e:
    kept = session.frames
    session.render(frames=2)  # goes on after the interruption
    found["session"] = {"frames": kept, "after": session.frames, "mean": float(session.image().mean()),
                        "seconds": time.monotonic() - started, "message": str(e)}

ctrl_c_in(2.0)
try:
    lightgraph.reference(scene="cornell-diffuse", res=(16, 16), frames=10**9, out=sys.argv[1])
    found["reference"] = "finished"
except KeyboardInterrupt as e:
    image, info = lightgraph.read(sys.argv[1])
    found["reference"] = {"frames": info["frames"], "message": str(e)}
print(json.dumps(found))
"""


def test_ctrl_c_stops_a_render_between_frames_and_keeps_the_film(tmp_path):
    film = tmp_path / "ref.exr"
    done = subprocess.run(
        [sys.executable, "-c", INTERRUPTED, str(film)], capture_output=True, text=True, timeout=180
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert "PanicException" not in done.stderr and "panicked" not in done.stderr, done.stderr[-3000:]
    found = json.loads(done.stdout.splitlines()[-1])
    render = found["render"]
    assert render != "finished" and render["shape"] == [16, 16, 3] and render["finite"], render
    assert render["message"].startswith("stopped at Ctrl-C"), render
    session = found["session"]
    assert session != "finished" and session["frames"] > 2 and session["after"] == session["frames"] + 2, session
    assert session["mean"] > 0 and session["seconds"] < 60, session
    assert f"keeps its {session['frames']} frames" in session["message"], session
    reference = found["reference"]
    assert reference != "finished" and reference["frames"] > 0, reference
    assert str(film) in reference["message"], reference


def test_the_notebook_runs(tmp_path):
    """docs/lab.ipynb runs from top to bottom (CI installs nbclient and ipykernel)."""
    if os.environ.get("LIGHTGRAPH_NOTEBOOK") != "required":
        pytest.importorskip("nbclient", reason="nbclient and ipykernel run docs/lab.ipynb (Debian: python3-nbclient python3-ipykernel)")
    import nbclient
    import nbformat

    notebook = nbformat.read(REPO / "docs" / "lab.ipynb", as_version=4)
    nbclient.NotebookClient(notebook, timeout=600, resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [o for cell in notebook.cells if cell.cell_type == "code" for o in cell.outputs]
    assert not [o for o in outputs if o.output_type == "error"], outputs
    shown = [o for o in outputs if o.output_type in ("display_data", "execute_result")]
    assert any("image/png" in o.data for o in shown), "the notebook shows no image"
    assert (tmp_path / "out" / "compare" / "curves.csv").exists()

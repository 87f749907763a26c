"""lightgraph: a GPU progressive light-transport lab, from Python.

Images are float32 numpy arrays of shape (height, width, 3) holding mean radiance. Keyword
arguments are the CLI's flags (``max_path_length=8`` is ``--max-path-length 8``,
``constants={"PM_RADIUS": 0.01}`` is ``--set PM_RADIUS=0.01``). A bad argument raises
``ValueError`` naming it (``frames=0: it must be at least 1``, ``constants['NO_SUCH']: graph
pt has no constant NO_SUCH; ...``) before any work; other errors raise :class:`Error` with
the CLI's message.
"""

from os import PathLike
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

Constant = Union[int, float, bool]
Path = Union[str, "PathLike[str]"]
Image = npt.NDArray[np.float32]
# A table of compare, study or verify: a pandas DataFrame when pandas is installed, else a
# dict of column name to numpy array (float64 for numbers, text otherwise).
Table = Any

class Error(Exception):
    """An error of lightgraph, with the CLI's message (file:line:column for bad files)."""

class Session:
    """A progressive render: frames accumulate into one image.

    ``render`` renders more frames with the interpreter released; ``image`` reads the mean
    so far. The scene is a built-in name (``lightgraph.list()["scenes"]``), a .ron scene file,
    a .gltf/.glb file or a Mitsuba .xml file.
    """

    def __init__(
        self,
        scene: str = "cornell-mitsuba",
        graph: str = "pt",
        layout: Optional[str] = None,
        spp: int = 1,
        res: Optional[Tuple[int, int]] = None,
        seed: int = 1,
        constants: Optional[Mapping[str, Constant]] = None,
        max_path_length: Optional[int] = None,
        bvh: str = "auto",
        adapter: Optional[str] = None,
    ) -> None:
        """Plans, compiles and instantiates ``graph`` in ``layout`` for ``scene``.

        Args:
            scene: a built-in scene name, a .ron scene file, a .gltf/.glb or a Mitsuba .xml file.
            graph: a built-in graph name or a .ron graph file.
            layout: one of the graph's layouts (None: its default).
            spp: samples per pixel in each frame, at least 1.
            res: (width, height), each at least 1 (None: the scene's).
            seed: the seed of the random streams, 0 to 4294967295.
            constants: graph constants to values, e.g. {"MAX_PATH_LENGTH": 8}; each must be a
                constant of the graph, of its type (u32, i32, f32 or bool).
            max_path_length: the longest path in segments, at least 1 (None: the scene's).
            bvh: "auto", "cwbvh" or "bvh2".
            adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
        """
    def render(self, frames: int = 1, time: Optional[float] = None) -> None:
        """Renders ``frames`` more frames, or as many as fit in ``time`` seconds. Ctrl-C
        stops it after the frames in flight and raises KeyboardInterrupt; the session keeps
        every frame rendered.

        Args:
            frames: frames to add, at least 1.
            time: seconds to render for, above zero (None: render ``frames``).
        """
    def image(self) -> npt.NDArray[np.float32]:
        """The mean image so far, shape (height, width, 3)."""
    def _repr_png_(self) -> bytes:
        """The mean image so far as a PNG file (sRGB, 8 bits), as Jupyter shows it."""
    def _repr_html_(self) -> str:
        """The mean image so far in the reports' viewer (exposure slider, zoom, values under
        the cursor; a self-contained page in an iframe) with its frames, as Jupyter shows it."""
    @property
    def frames(self) -> int:
        """Frames rendered so far."""
    def stats(self) -> dict[str, Any]:
        """frames, samples (per pixel), rays, seconds (of rendering calls) and adapter."""

def render(
    scene: str = "cornell-mitsuba",
    graph: str = "pt",
    layout: Optional[str] = None,
    spp: int = 1,
    res: Optional[Tuple[int, int]] = None,
    seed: int = 1,
    frames: int = 64,
    time: Optional[float] = None,
    constants: Optional[Mapping[str, Constant]] = None,
    max_path_length: Optional[int] = None,
    bvh: str = "auto",
    adapter: Optional[str] = None,
) -> Tuple[npt.NDArray[np.float32], dict[str, Any]]:
    """Renders ``frames`` frames (or for ``time`` seconds) and returns the mean image and
    the statistics (frames, samples, rays, seconds, adapter), as ``lightgraph render`` with
    the same options and seed renders it. Ctrl-C stops it after the frames in flight and
    raises KeyboardInterrupt carrying the film so far as its ``image`` and ``stats``.

    Args:
        scene: a built-in scene name, a .ron scene file, a .gltf/.glb or a Mitsuba .xml file.
        graph: a built-in graph name or a .ron graph file.
        layout: one of the graph's layouts (None: its default).
        spp: samples per pixel in each frame, at least 1.
        res: (width, height), each at least 1 (None: the scene's).
        seed: the seed of the random streams, 0 to 4294967295.
        frames: frames to render, at least 1.
        time: seconds to render for, above zero (None: render ``frames``).
        constants: graph constants to values, e.g. {"MAX_PATH_LENGTH": 8}; each must be a
            constant of the graph, of its type (u32, i32, f32 or bool).
        max_path_length: the longest path in segments, at least 1 (None: the scene's).
        bvh: "auto", "cwbvh" or "bvh2".
        adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
    """

def reference(
    scene: str = "cornell-mitsuba",
    out: Path = "out/reference.exr",
    graph: str = "pt",
    layout: Optional[str] = None,
    spp: int = 1,
    res: Optional[Tuple[int, int]] = None,
    seed: Optional[int] = None,
    frames: Optional[int] = None,
    time: Optional[float] = None,
    constants: Optional[Mapping[str, Constant]] = None,
    max_path_length: Optional[int] = None,
    bvh: str = "auto",
    adapter: Optional[str] = None,
    resume: Optional[Path] = None,
) -> npt.NDArray[np.float32]:
    """Renders a reference film (f64 sums, variance, settings) for ``frames`` frames or
    ``time`` seconds, writes it to ``out`` and returns its mean image. Ctrl-C stops it
    after the frames in flight, writes the film and raises KeyboardInterrupt saying so.

    Args:
        out: the film's path (an EXR; the PNG preview goes beside it).
        scene: a built-in scene name, a .ron scene file, a .gltf/.glb or a Mitsuba .xml file.
        graph: a built-in graph name or a .ron graph file.
        layout: one of the graph's layouts (None: its default).
        spp: samples per pixel in each frame, at least 1.
        res: (width, height), each at least 1 (None: the scene's).
        seed: the seed of the random streams, 0 to 4294967295 (None: 1000003).
        frames: the frames the film holds at the end, at least 1 (64 when neither frames
            nor time is given); with resume, its frames included (a film of 64 frames
            resumed with frames=256 gets 192 more; one that holds as many already raises
            ValueError before any work).
        time: seconds to render for, above zero (with resume, the time added to the film's).
        constants: graph constants to values, e.g. {"MAX_PATH_LENGTH": 8}; each must be a
            constant of the graph, of its type (u32, i32, f32 or bool).
        max_path_length: the longest path in segments, at least 1 (None: the scene's).
        bvh: "auto", "cwbvh" or "bvh2".
        adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
        resume: a film to continue with more frames of the same random streams (its
            resolution, seed and constants are the defaults of those not given; scene,
            graph and spp must be its own).
    """

def compare(
    reference: Path,
    runs: str,
    time: float = 10.0,
    seed: int = 1,
    out: Path = "out/compare",
    per_decade: int = 6,
    baseline: Optional[str] = None,
    adapter: Optional[str] = None,
) -> Dict[str, Any]:
    """Runs each of ``runs`` for ``time`` seconds against the reference film, writes
    curves.csv, rmse_vs_time.png, summary.md and each run's image into ``out``, and returns
    a dict: ``summary`` (Markdown), ``curves`` (curves.csv as a :data:`Table`), ``images``
    (each run's mean image by run label) and ``reference`` (the reference's mean image).
    Ctrl-C stops it after the frames in flight (KeyboardInterrupt saying what was kept).

    Args:
        reference: the reference film (from ``reference``).
        runs: ``graph[:layout][@NAME=VALUE...]``, comma-separated.
        time: seconds each run renders for, above zero.
        seed: the seed of the random streams, 0 to 4294967295.
        out: the folder of the comparison.
        per_decade: error samples per decade of time, at least 1.
        baseline: the run the others' speed-ups are against (None: the first).
        adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
    """

def study(
    scenes: Sequence[str],
    estimators: Optional[Sequence[str]] = None,
    time: float = 20.0,
    reference_time: float = 120.0,
    reference_graph: str = "vcm",
    res: Optional[Tuple[int, int]] = None,
    seed: int = 1,
    out: Path = "out/study",
    adapter: Optional[str] = None,
) -> Dict[str, Any]:
    """Runs each estimator on each scene against a reference per scene, writes each scene's
    comparison and summary.md, summary.csv and layouts.csv into ``out``, and returns a dict:
    ``summary`` (Markdown), ``table`` (summary.csv), ``layouts`` (layouts.csv) and ``scenes``:
    per scene folder ``curves`` (its curves.csv), ``images`` (each run's mean image by run
    label) and ``reference`` (its reference's mean image); tables are :data:`Table`s.

    Args:
        scenes: the scenes, as ``scene`` of ``render`` takes them.
        estimators: ``graph`` (its fastest layout on each scene) or ``graph:Layout``
            entries (None: PT, LVC-BPT, PPM, SPPM, PBPM and VCM).
        time: seconds of rendering per estimator and scene, above zero.
        reference_time: seconds of each missing reference, above zero (found in, resumed
            into or rendered into ``out/references``).
        reference_graph: the graph that renders the references.
        res: (width, height), each at least 1 (None: each scene's).
        seed: the seed of the random streams, 0 to 4294967295.
        out: the folder of the study.
        adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
    """

def verify(
    scenes: Optional[Sequence[str]] = None,
    graphs: Optional[Sequence[str]] = None,
    add: Optional[Sequence[str]] = None,
    time: Optional[float] = None,
    frames: Optional[int] = None,
    batches: Optional[int] = None,
    block: Optional[int] = None,
    res: Optional[Tuple[int, int]] = None,
    seed: int = 1,
    out: Path = "out/verify",
    adapter: Optional[str] = None,
    preset: Optional[str] = None,
) -> Dict[str, Any]:
    """Every estimator on every scene in batches, every pair tested for a difference beyond
    their noise (``lightgraph verify``); writes verify.md, verify.csv, each run's image per
    scene folder and a map of every pair that differs into ``out``, and returns a dict:
    ``summary`` (Markdown), ``table`` (verify.csv as a :data:`Table`: a row per scene and
    pair, with its verdict), ``scenes``: per scene folder ``images`` (each estimator's mean
    image), and ``failed``: None, or the message with which ``lightgraph verify`` fails (a
    difference nothing predicts, or pairs the budget could not decide), returned with the
    tables rather than raised.

    Args:
        scenes: the scenes, as ``scene`` of ``render`` takes them (None: the six Cornell boxes).
        graphs: estimators, ``graph[:Layout][@NAME=VALUE...]`` (None: every built-in graph of
            radiance, and VCM's two halves alone).
        add: estimators verified besides those of ``graphs``, e.g. your own graph file.
        time: seconds each estimator renders each scene, above zero (None: the preset's
            budget, else 10).
        frames: frames of each estimator on each scene instead of a time (reproducible; it
            wins over ``time``).
        batches: batches each run is split into, at least 2 (None: the preset's, else 16).
        block: side of the blocks compared, in pixels, at least 1 (None: the preset's, else 16).
        res: (width, height), each at least 1 (None: the preset's, else each scene's).
        seed: the seed of the random streams, 0 to 4294967295.
        out: the folder of the verification.
        adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
        preset: ``"lavapipe"`` or ``"gpu"``: the size, samples per pixel, budget, batches,
            blocks and power of ``lightgraph verify --preset`` (lavapipe's for a software
            rasteriser, gpu's for a GPU). Each of time, frames, batches, block and res given
            wins.
    """

def to_png(image: Image, exposure: float = 0.0) -> bytes:
    """The PNG file of an image (shape (height, width, 3)) at ``exposure`` stops, sRGB in 8
    bits as the CLI's previews; in Jupyter: ``IPython.display.Image(lightgraph.to_png(image))``.

    Args:
        image: float32 linear radiance of shape (height, width, 3).
        exposure: stops to scale the radiance by (2 ** exposure) before the sRGB curve.
    """

def explain(
    graph: str = "pt",
    layout: Optional[str] = None,
    scene: str = "cornell-mitsuba",
    res: Optional[Tuple[int, int]] = None,
    spp: int = 1,
    constants: Optional[Mapping[str, Constant]] = None,
    all_features: bool = False,
    adapter: Optional[str] = None,
) -> str:
    """The kernels, schedule and memory of the graph's layouts (all, or ``layout``).

    Args:
        graph: a built-in graph name or a .ron graph file.
        layout: one of the graph's layouts (None: all of them).
        scene: a built-in scene name, a .ron scene file, a .gltf/.glb or a Mitsuba .xml file.
        res: (width, height), each at least 1 (None: the scene's).
        spp: samples per pixel in each frame, at least 1.
        constants: graph constants to values; each must be a constant of the graph, of its
            type.
        all_features: compile every scene feature into the kernels, not only the scene's.
        adapter: the GPU: an index, a PCI bus id or text of its name (None: the default).
    """

def list() -> dict[str, Any]:
    """Built-in ``scenes`` (name to file), ``graphs`` and GPU ``adapters``."""

def read(path: Path) -> Tuple[npt.NDArray[np.float32], dict[str, Any]]:
    """Reads a film (EXR from render, reference or merge): its mean image and its settings
    and statistics (its attributes as text, and samples per pixel, frames, seconds).

    Args:
        path: the film's path.
    """

def cli(args: Sequence[str]) -> None:
    """Runs a ``lightgraph`` command line without the program name, e.g.
    ``cli(["merge", "a.exr", "b.exr", "--out", "m.exr"])``; its errors raise :class:`Error`.

    Args:
        args: the command and its options, as strings.
    """

"""lightgraph: a GPU progressive light-transport lab, from Python.

Images are float32 numpy arrays of shape (height, width, 3) holding mean radiance. Keyword
arguments are the CLI's flags (``max_path_length=8`` is ``--max-path-length 8``,
``constants={"PM_RADIUS": 0.01}`` is ``--set PM_RADIUS=0.01``) and are checked as the CLI
checks them. Errors raise :class:`Error` with the CLI's message.
"""

from os import PathLike
from typing import Any, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

Constant = Union[int, float, bool]
Path = Union[str, "PathLike[str]"]

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
    ) -> None: ...
    def render(self, frames: int = 1, time: Optional[float] = None) -> None:
        """Renders ``frames`` more frames, or as many as fit in ``time`` seconds."""
    def image(self) -> npt.NDArray[np.float32]:
        """The mean image so far, shape (height, width, 3)."""
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
    the same options and seed renders it."""

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
    """Renders a reference film (f64 sums, variance, settings; seed 1000003 by default) for
    ``frames`` frames (64 when neither frames nor time is given) or ``time`` seconds, writes
    it to ``out`` and returns its mean image."""

def compare(
    reference: Path,
    runs: str,
    time: float = 10.0,
    seed: int = 1,
    out: Path = "out/compare",
    per_decade: int = 6,
    baseline: Optional[str] = None,
    adapter: Optional[str] = None,
) -> str:
    """Runs each of ``runs`` (``graph[:layout][@NAME=VALUE...]``, comma-separated) for
    ``time`` seconds against the reference film, writes curves.csv, rmse_vs_time.png,
    summary.md and each run's image into ``out``, and returns the summary (Markdown)."""

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
) -> str:
    """Runs each of ``estimators`` (a graph for its fastest layout on each scene, or
    ``graph:Layout``; default PT, LVC-BPT, PPM, SPPM, PBPM and VCM) for ``time`` seconds of
    rendering on each of ``scenes`` against a reference per scene (found in, resumed into or
    rendered into ``out/references`` with ``reference_graph`` for ``reference_time``
    seconds), writes each scene's comparison and summary.md, summary.csv and layouts.csv
    into ``out``, and returns the summary (Markdown)."""

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
    """The kernels, schedule and memory of the graph's layouts (all, or ``layout``)."""

def list() -> dict[str, Any]:
    """Built-in ``scenes`` (name to file), ``graphs`` and GPU ``adapters``."""

def read(path: Path) -> Tuple[npt.NDArray[np.float32], dict[str, Any]]:
    """Reads a film (EXR from render, reference or merge): its mean image and its settings
    and statistics (its attributes as text, and samples per pixel, frames, seconds)."""

def cli(args: Sequence[str]) -> None:
    """Runs a ``lightgraph`` command line without the program name, e.g.
    ``cli(["merge", "a.exr", "b.exr", "--out", "m.exr"])``."""

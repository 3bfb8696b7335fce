"""Type stubs of illum's native module (python/src/lib.rs)."""
from os import PathLike
from typing import Any

import numpy as np
import numpy.typing as npt

class IllumError(Exception):
    """Bad input (the message names the file, field and value), an unusable device, a failed write."""

class Scene:
    """A validated scene."""

    @staticmethod
    def from_dict(d: dict[str, Any], base_dir: str | PathLike[str] | None = None) -> Scene:
        """A scene from a dict of the JSON scene format, validated as a scene file is."""
    @property
    def resolution(self) -> tuple[int, int]:
        """The camera's (width, height)."""
    @property
    def warnings(self) -> list[str]:
        """What the file holds that illum does not render (a USD stage's prim and attribute)."""
    def render(
        self,
        spp: int | None = None,
        time: float | None = None,
        seed: int = 0,
        integrator: str | None = None,
        width: int | None = None,
        height: int | None = None,
        trace: str = "auto",
        device: str | None = None,
        report: bool = False,
        samples: tuple[int, int] | None = None,
        crop: tuple[int, int, int, int] | None = None,
        **params: Any,
    ) -> Render:
        """Renders as `illum render` does with the same settings (the same pixels bit for bit).

        `samples=(a, b)` and `crop=(x0, y0, x1, y1)` render one job of a split render (its
        `write` writes the partial EXR; `merge` joins the jobs).

        `params` are the integrator's parameters (`--param NAME=VALUE`; booleans for on/off).
        Ctrl-C stops the render and returns the samples done (`Render.interrupted`)."""

class Render:
    """A render's planes as float32 arrays (height, width[, 3]), its header and its report."""

    beauty: npt.NDArray[np.float32]
    albedo: npt.NDArray[np.float32]
    normal: npt.NDArray[np.float32]
    depth: npt.NDArray[np.float32]
    emission: npt.NDArray[np.float32]
    variance: npt.NDArray[np.float32] | None
    samples: npt.NDArray[np.float32]
    """Samples each pixel took: a job's of its own range; witness pixels twice the spp."""
    aovs: dict[str, npt.NDArray[np.float32]]
    metadata: dict[str, str]
    report: dict[str, npt.NDArray[np.float64]]
    """Per pass (report=True; else the last): spp, wall_seconds, device_seconds,
    estimated_relmse, relmse (against compare's reference; NaN where unknown)."""
    spp: int
    interrupted: bool
    @property
    def resolution(self) -> tuple[int, int]: ...
    @property
    def job(self) -> tuple[tuple[int, int], tuple[int, int, int, int], tuple[int, int]] | None:
        """A job's samples (a, b), window (x0, y0, x1, y1) and frame (width, height), else None."""
    def write(self, path: str | PathLike[str]) -> None:
        """Writes an EXR (every plane, the header of `illum render`) or, for .png, a PNG."""

class Prepared:
    """A scene uploaded once (trace structure, kernels): renders again and takes edits, each
    rewriting only what it changes; its renders equal fresh loads of the edited scene."""

    def set_light(self, name: str, **fields: Any) -> None:
        """Sets fields of light `name` as the scene format names them (intensity, color, ...)."""
    def set_material(self, name: str, **fields: Any) -> None:
        """Sets fields of material `name` (diffuse, specular, emission, ...)."""
    def set_camera(self, **fields: Any) -> None:
        """Sets fields of the camera (position, look_at, up, fov_y, resolution)."""
    def set_transform(self, name: str, transform: Any) -> None:
        """Sets shape `name`'s transform (the scene format's `transform`)."""
    @property
    def scene(self) -> Scene:
        """The scene as edited so far."""
    def render(
        self,
        spp: int | None = None,
        time: float | None = None,
        seed: int = 0,
        integrator: str | None = None,
        report: bool = False,
        **params: Any,
    ) -> Render:
        """Renders as Scene.render does, without uploading the scene again."""

def prepare(scene: Scene, trace: str = "auto", device: str | None = None) -> Prepared:
    """Uploads `scene` once for repeated renders and edits."""

def merge(parts: list[Render] | list[str | PathLike[str]]) -> Render:
    """Joins the jobs of a split render (results or partial EXRs) into the whole image, bit for bit."""

class Comparison:
    """A comparison's runs: each one's render by name and the table `illum compare` prints."""

    names: list[str]
    renders: dict[str, Render]
    table: list[dict[str, Any]]
    measured: bool
    kind: str

def compare(
    scene: Scene,
    time: float = 5.0,
    techniques: list[str] | str | None = None,
    integrators: list[str] | str | None = None,
    samples: list[str] | str | None = None,
    reference: str | PathLike[str] | npt.ArrayLike | None = None,
    seed: int = 0,
    integrator: str | None = None,
    width: int | None = None,
    height: int | None = None,
    trace: str = "auto",
    device: str | None = None,
    output: str | PathLike[str] | None = None,
    **params: Any,
) -> Comparison:
    """Renders each run for `time` seconds as `illum compare` does with the same options.

    `techniques` (brdf, light, mis), `integrators` (direct, full, path, full-nocache,
    full-nocaustics) and `samples` ("L/B", "L/B/dmis", "L/B/nodmis") as the CLI's options;
    `reference` an EXR's path or a (height, width, 3) array (else the relMSE is estimated from
    the half-buffers); `output=PREFIX` writes PREFIX-<name>.exr, PREFIX-error.png and
    PREFIX-strip.png (each EXR as its run ends). Ctrl-C raises KeyboardInterrupt after writing
    the EXR of the run it stopped."""

def load(path: str | PathLike[str]) -> Scene:
    """Loads and validates a scene file: JSON, or a USD stage (.usd, .usda, .usdc, .usdz)."""

def default_scene() -> Scene:
    """The built-in default scene."""

def devices() -> list[dict[str, Any]]:
    """Every Vulkan device illum sees (what `illum devices` prints)."""

def validation_messages() -> list[str]:
    """The Vulkan validation layers' messages so far (with ILLUM_VALIDATION=1)."""

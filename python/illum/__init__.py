"""illum from Python: load or build a scene, render it with illum's own driver into NumPy arrays,
write it as `illum render` does.

    import illum
    scene = illum.load("scenes/interior.json")
    r = scene.render(spp=64, integrator="full")
    r.beauty.shape        # (240, 320, 3), float32
    r.write("interior.exr")

Errors are `illum.IllumError`, with the message the command line prints.
"""
from ._illum import (
    Comparison,
    IllumError,
    Prepared,
    Render,
    Scene,
    compare,
    default_scene,
    devices,
    load,
    merge,
    prepare,
    validation_messages,
)

__all__ = [
    "Comparison",
    "IllumError",
    "Prepared",
    "Render",
    "Scene",
    "compare",
    "default_scene",
    "devices",
    "load",
    "merge",
    "prepare",
    "validation_messages",
]

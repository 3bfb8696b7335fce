"""What the Python tests share: the CLI they compare against (ILLUM_BIN, set by scripts/test.sh),
its scenes, and the check that no test draws a validation message."""
import os
import pathlib
import subprocess

import numpy as np
import OpenEXR
import pytest

import illum

ROOT = pathlib.Path(__file__).resolve().parents[2]
BIN = os.environ.get("ILLUM_BIN", str(ROOT / "target" / "release" / "illum"))
INTERIOR = ROOT / "scenes" / "interior.json"


@pytest.fixture(autouse=True)
def no_validation_messages():
    """Every test runs with the validation layers on (ILLUM_VALIDATION=1, scripts/test.sh) and
    fails on any message they give."""
    yield
    assert illum.validation_messages() == []


def channels(path):
    """Every channel of an EXR as float32 arrays, by name."""
    with OpenEXR.File(str(path), separate_channels=True) as f:
        return {name: np.array(c.pixels, dtype=np.float32) for name, c in f.channels().items()}


def cli(*args):
    return subprocess.run([BIN, *map(str, args)], capture_output=True, text=True)

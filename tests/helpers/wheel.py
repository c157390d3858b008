"""The project's wheel, built from a copy of the checkout, and installed without -e into a folder
of its own: what a user's ``pip install .`` puts on a machine."""

import shutil
import subprocess
import sys
from pathlib import Path

from tests.helpers.paths import ROOT


def build_wheel(out: Path) -> Path:
    """The wheel of the checkout, in ``out``. From a copy: setuptools builds in the source folder,
    and build/ there could hold stale files."""
    source = out / "source"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(".git", ".tox", "build", "*.egg-info"))
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--quiet",
            "--no-deps",
            "--no-build-isolation",
            "-w",
            str(out),
            str(source),
        ],
        check=True,
        capture_output=True,
    )
    (built,) = out.glob("speech_event-*.whl")
    return built


def install(wheel: Path, target: Path) -> Path:
    """``wheel`` installed into ``target`` (no dependencies: they are this Python's)."""
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--target", str(target), str(wheel)],
        check=True,
        capture_output=True,
    )
    return target

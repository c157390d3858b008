"""Runs the deployment node's script the way roslaunch and users do."""

import os
import subprocess
import sys

from tests.helpers.paths import ROOT

APPLICATION = ROOT / "scripts" / "speech_event_application.py"


def run_application(*arguments: str) -> "subprocess.CompletedProcess[str]":
    """The script run to its end, outside ROS: for what it does before it touches ROS."""
    return subprocess.run(
        [sys.executable, str(APPLICATION), *arguments],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
    )

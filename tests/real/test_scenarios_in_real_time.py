"""Every scenario played to the node in real time on the in-memory bus, beside two busy processes,
publishes what it publishes on the fake clock (issue 30, item 2; issue 56, item 2): the node's
timers are threads, its recognitions run on its worker thread, partial results and speculation run
as on the robot, and eight replays (``python -m harness run --real-time``) run side by side with
two processes spinning, so each gets much less than a core, at moments no one chose. What is
compared is what a real-time replay compares (harness/report.py): the texts in their order, the
soundDetection errors in theirs, service responses and action results; the deadline for a text is
the harness's."""

import os
import subprocess
import sys
from pathlib import Path
from typing import List

from fixtures.load import cores_kept_busy
from fixtures.paths import ROOT
from fixtures.scenario_files import ALL_SCENARIOS, shard

SIDE_BY_SIDE = 8  # about 500 s of scenarios: a minute or two of wall clock in eight parts


def _replay(scenarios: List[Path]) -> "subprocess.Popen[str]":
    return subprocess.Popen(
        [sys.executable, "-m", "harness", "run", "--real-time", *[str(path) for path in scenarios]],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_every_scenario_in_real_time_beside_two_busy_processes_publishes_what_it_publishes_on_the_fake_clock() -> (
    None
):
    parts = [shard(ALL_SCENARIOS, index, SIDE_BY_SIDE) for index in range(SIDE_BY_SIDE)]
    with cores_kept_busy():
        replays = [_replay(part) for part in parts]
        outputs = [replay.communicate(timeout=900) for replay in replays]
    for part, (stdout, stderr) in zip(parts, outputs):
        lines = stdout.splitlines()
        assert lines[-1] == f"{len(part)} passed, 0 failed", stdout + stderr
        assert [line.split("  ")[0] for line in lines if line.startswith(("PASS", "FAIL"))] == ["PASS"] * len(
            part
        )
    assert sum(len(part) for part in parts) == len(ALL_SCENARIOS) > 50

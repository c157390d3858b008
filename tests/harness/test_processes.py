"""harness/processes.py: every process a replay starts is stopped, also when a Ctrl-C comes while
it starts one."""

import signal
import subprocess
import sys
from pathlib import Path
from typing import Any, List

import pytest

from harness.processes import Processes


def test_a_ctrl_c_that_comes_as_a_process_starts_still_finds_it_on_the_list(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The Ctrl-C lands right after the fork, before Popen has returned: it is held until the
    process is on the list, so stop_all stops it (before, the node it started outlived the replay).
    Passes also where the test runs with SIGINT ignored (CI's run as a background job failed it)."""
    started: List[subprocess.Popen[str]] = []
    popen = subprocess.Popen

    def interrupted_popen(*arguments: Any, **keywords: Any) -> "subprocess.Popen[str]":
        process = popen(*arguments, **keywords)
        started.append(process)
        signal.raise_signal(signal.SIGINT)  # Python runs the handler before this returns
        return process

    monkeypatch.setattr(subprocess, "Popen", interrupted_popen)
    # Python's own Ctrl-C handler, as an interactive replay has it; a Python started with SIGINT
    # ignored (a script's background job, `.ci/run &`) keeps ignoring it, and no Ctrl-C comes.
    ignored = signal.signal(signal.SIGINT, signal.default_int_handler)
    processes = Processes({}, tmp_path)
    try:
        with pytest.raises(KeyboardInterrupt):
            processes.start("sleeper", [sys.executable, "-c", "import time; time.sleep(60)"])
        (process,) = started
        assert process.poll() is None
        processes.stop_all()
        assert process.poll() is not None
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # as it was
    finally:
        signal.signal(signal.SIGINT, ignored)

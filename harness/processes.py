"""The process supervisor of the replays, the ROS tests and the bench: imports nothing of ROS.

Each process starts in a process group of its own, logs to a file of its own, and is stopped with
everything below it (roslaunch starts rosmaster and rosout in sessions of their own), also on
failure or Ctrl-C.
"""

import contextlib
import os
import signal
import socket
import subprocess
import threading
import time
from contextlib import closing
from pathlib import Path
from typing import Callable, Dict, Iterator, List, Sequence, Set

# How long a replay waits for one real event (a message received, a connection made or dropped).
EVENT_TIMEOUT = 20.0
# The longest pause between two polls of a condition (wait_until).
POLL_AT_MOST = 0.02


class ReplayError(Exception):
    """A replay could not go on: a process it needs did not start, answer or stop."""


def wait_until(condition: Callable[[], bool], what: str, timeout: float = EVENT_TIMEOUT) -> None:
    """Poll ``condition`` until it holds; a ReplayError naming ``what`` after ``timeout`` s.

    The first polls follow each other closely (most events come within milliseconds), then ever
    more slowly up to 20 ms: a condition is an XML-RPC call to the node or the master, and polling
    every 2 ms took the CPU the node needed on a busy machine."""
    deadline = time.monotonic() + timeout
    pause = 0.001
    while not condition():
        if time.monotonic() > deadline:
            raise ReplayError(f"gave up after {timeout:.0f} s waiting for {what}")
        time.sleep(pause)
        pause = min(2 * pause, POLL_AT_MOST)


def descendants(pid: int) -> Set[int]:
    """Every live process below ``pid``, from /proc: roslaunch starts rosmaster and rosout in
    sessions of their own, out of reach of a signal to roscore's process group."""
    parents: Dict[int, int] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            parents[int(stat.parent.name)] = int(stat.read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):  # the process ended while being read
            continue
    found: Set[int] = set()
    frontier = {pid}
    while frontier:
        frontier = {child for child, parent in parents.items() if parent in frontier}
        found |= frontier
    return found


@contextlib.contextmanager
def _interrupts_deferred() -> Iterator[None]:
    """Ctrl-C or SIGTERM (harness/cli.py) waits until a process just started is on the list that
    stop_all stops: one that came between the fork and the list left the child running, unknown
    to it (a node outlived an interrupted replay under load). Python's handlers only: the child
    execs with the default ones. In the main thread, where handlers live; elsewhere as it was."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    arrived: List[int] = []

    def note(number: int, frame: object) -> None:
        arrived.append(number)

    handlers = {number: signal.signal(number, note) for number in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for number, handler in handlers.items():
            signal.signal(number, handler)
        for first in arrived[:1]:
            handler = handlers[signal.Signals(first)]
            if callable(handler):
                handler(first, None)
            elif handler == signal.SIG_DFL:
                signal.raise_signal(first)


def free_port() -> int:
    """A TCP port on loopback that nothing listens on now."""
    with closing(socket.socket(socket.AF_INET, socket.SOCK_STREAM)) as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


class Processes:
    """Every process the runner starts, each in its own process group, all stopped at the end."""

    def __init__(self, environment: Dict[str, str], log_dir: Path) -> None:
        self._environment = environment
        self._log_dir = log_dir
        self._started: List[subprocess.Popen] = []  # type: ignore[type-arg]

    def start(self, name: str, command: Sequence[str], talk: bool = False) -> "subprocess.Popen[str]":
        # The child holds its own copy of the log's descriptor; ours closes once it has started.
        with open(self.log(name), "a") as log, _interrupts_deferred():
            try:
                process = subprocess.Popen(
                    list(command),
                    env=self._environment,
                    stdin=subprocess.PIPE if talk else subprocess.DEVNULL,
                    stdout=subprocess.PIPE if talk else log,
                    stderr=log,
                    text=True,
                    start_new_session=True,
                )
            except OSError as problem:  # no such executable, not executable
                raise ReplayError(f"cannot start the {name} ({command[0]}): {problem.strerror}") from None
            self._started.append(process)
        return process

    def log(self, name: str) -> Path:
        return self._log_dir / f"{name}.log"

    def last_lines(self, name: str, count: int = 15) -> str:
        """The end of a process's log, for an error that must say why it died."""
        try:
            lines = self.log(name).read_text(errors="replace").splitlines()
        except OSError:
            return "(no output)"
        return "\n".join(lines[-count:]) or "(no output)"

    def stop(self, *processes: "subprocess.Popen[str]", grace: float = 5.0) -> None:
        """SIGINT to each of ``processes`` (and its process group) at once, then wait for all:
        a rospy node takes most of a second to shut down, and a replay stops two or more at the
        end of every scenario. SIGKILL for what is left after ``grace`` seconds."""
        running = [process for process in processes if process.poll() is None]
        families = [descendants(process.pid) for process in running]  # orphans leave the tree
        for process in running:
            with contextlib.suppress(ProcessLookupError):  # it may have gone already
                os.killpg(process.pid, signal.SIGINT)
        deadline = time.monotonic() + grace
        for process in running:
            try:
                process.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(process.pid, signal.SIGKILL)
                process.wait()
        family = [pid for pids in families for pid in pids]
        deadline = time.monotonic() + grace
        while any(Path(f"/proc/{pid}").exists() for pid in family) and time.monotonic() < deadline:
            time.sleep(0.05)  # a clean roscore stops its rosmaster and rosout itself
        for pid in family:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)

    def stop_all(self) -> None:
        # one by one, the last started first: the nodes unregister while their roscore still runs
        for process in reversed(self._started):
            self.stop(process)

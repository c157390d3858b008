"""The processes a test started: this process's children, read from /proc (Linux)."""

import os
from pathlib import Path
from typing import Set


def children() -> Set[int]:
    """The ids of this process's child processes, zombies (ended, not yet waited for) included."""
    found = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rpartition(")")[2].split()  # after the name, which may hold spaces
        except OSError:  # it ended meanwhile
            continue
        if int(fields[1]) == os.getpid():
            found.add(int(stat.parent.name))
    return found


def running(pid: int) -> bool:
    """Whether process ``pid`` exists (a zombie too: it was not waited for)."""
    return Path(f"/proc/{pid}").exists()

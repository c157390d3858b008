"""Other processes keeping the cores busy, as on a machine with other work running (issues 30 and
56): what the node publishes must not depend on how much CPU it gets."""

import subprocess
import sys
from contextlib import contextmanager
from typing import Iterator

# Two: as many as the machine's cores, so the tests beside them get what a loaded machine leaves.
BUSY_PROCESSES = 2


@contextmanager
def cores_kept_busy(count: int = BUSY_PROCESSES) -> Iterator[None]:
    """``count`` processes spinning for as long as the block runs; stopped after it."""
    burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)]
    try:
        yield
    finally:
        for burner in burners:
            burner.kill()
            burner.wait()

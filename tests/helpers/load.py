"""Another process keeping a core busy, as on a machine with other work running (issue 30): what the
node publishes must not depend on how much CPU it gets."""

import subprocess
import sys
from contextlib import contextmanager
from typing import Iterator


@contextmanager
def a_core_kept_busy() -> Iterator[None]:
    """A process spinning on one core for as long as the block runs; stopped after it."""
    burner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        yield
    finally:
        burner.kill()
        burner.wait()

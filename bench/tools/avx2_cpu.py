"""Run a command as an AVX2 CPU without AVX-512 would, natively: bench/tools/avx2_cpu.c, built with the
C compiler here and loaded with LD_PRELOAD, hides the AVX-512 and AVX-VNNI features from CPUID, so
onnxruntime and numpy choose the kernels a robot's AVX2 CPU runs. It needs a CPU that can make CPUID
fault (``cpuid_fault`` in /proc/cpuinfo; Intel's since Ivy Bridge, and virtual machines under KVM).

Checked against Debian's qemu-user running the process as a Haswell (``qemu-x86_64 -cpu Haswell-v4``,
50 to 100 times slower): the test's random Whisper with 8-bit weights, one scale a matrix, is off
fp32's logits by 13.0 % of the largest logit under both, 2.4 % here natively (docs/models.md).

    python -m bench.tools.avx2_cpu COMMAND [ARGUMENTS...]
"""

import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Dict, List

SOURCE = Path(__file__).with_name("avx2_cpu.c")


def build(folder: Path) -> Path:
    """The shared library built from avx2_cpu.c into ``folder``."""
    library = folder / "avx2_cpu.so"
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-o", str(library), str(SOURCE)], check=True)
    return library


def environment(library: Path) -> Dict[str, str]:
    """This process's environment, with ``library`` preloaded into what it starts."""
    preload = " ".join(filter(None, [str(library), os.environ.get("LD_PRELOAD", "")]))
    return {**os.environ, "LD_PRELOAD": preload}


def main(command: List[str]) -> int:
    if not command:
        sys.exit(__doc__)
    with tempfile.TemporaryDirectory(prefix="avx2_cpu_") as folder:
        return subprocess.run(command, env=environment(build(Path(folder)))).returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

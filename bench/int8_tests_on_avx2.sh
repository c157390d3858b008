#!/usr/bin/env bash
# The int8 tests on an AVX2 CPU without AVX-512, whatever CPU this is: Debian's qemu-user runs the
# test Python as a Haswell (apt-get install qemu-user), so onnxruntime picks the int8 kernels a
# robot's AVX2 CPU runs. Not in CI: emulated, they take about 100 times as long (docs/models.md
# says how long). Run it from the repository root after `tox -e py` has made .tox/py; arguments go
# to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
python="${PYTHON:-.tox/py/bin/python}"
grep -qw avx512f /proc/cpuinfo && echo "this CPU has AVX-512; the tests run as a Haswell (AVX2 only)"
exec qemu-x86_64 -cpu Haswell-v4 "$python" -m pytest -p no:cacheprovider -p no:xdist -q \
    tests/exporters tests/recognizers tests/test_pull.py -k "int8 or quantiz" "$@"

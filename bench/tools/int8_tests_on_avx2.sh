#!/usr/bin/env bash
# The int8 tests on an AVX2 CPU without AVX-512, whatever CPU this is: bench/tools/avx2_cpu.py runs the
# test Python natively with CPUID answering without AVX-512 and AVX-VNNI, so onnxruntime and numpy
# pick the kernels a robot's AVX2 CPU runs (it needs cpuid_fault in /proc/cpuinfo). With QEMU=1,
# Debian's qemu-user runs it as a Haswell instead (apt-get install qemu-user; about 100 times as
# long). Run it from the repository root after `tox -e py` has made .tox/py; arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/../.."
python="${PYTHON:-.tox/py/bin/python}"
grep -qw avx512f /proc/cpuinfo && echo "this CPU has AVX-512; the tests run as an AVX2 CPU without it"
# pytest's faulthandler would take SIGSEGV, which answers CPUID here
tests=(-m pytest -p no:cacheprovider -p no:xdist -p no:faulthandler -q
    tests/exporters tests/recognizers tests/models/test_pull.py -k "int8 or quantiz" "$@")
if [[ "${QEMU:-0}" == 1 ]]; then
    exec qemu-x86_64 -cpu Haswell-v4 "$python" "${tests[@]}"
fi
exec "$python" -m bench.tools.avx2_cpu "$python" "${tests[@]}"

#!/bin/bash
# Mutation score of the core steps (validate, assembly, transcript; interfaces/periodic): mutmut 3
# on a scratch copy of this checkout, running only those steps' tests. Prints killed/total per module
# and overall, then the survivors. Needs mutmut>=3 beside pytest (python -m pip install mutmut); takes minutes.
#   bash bench/tools/mutation.sh [PYTHON]     (default: python3; the test environment's interpreter)
set -euo pipefail
python=${1:-python3}
mutmut="$(dirname "$("$python" -c 'import sys; print(sys.executable)')")/mutmut"
checkout=$(cd "$(dirname "$0")/../.." && pwd)
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
# Without the folders the tools write as they run (a test session beside this one writes
# .hypothesis: tar said "file changed as we read it" and failed the py env).
tar -C "$checkout" --exclude=./.git --exclude=./.tox --exclude=./mutants --exclude='*.egg-info' \
    --exclude=__pycache__ --exclude=./.hypothesis --exclude=./.pytest_cache --exclude=./.mypy_cache \
    --exclude=./.ruff_cache -cf - . | tar -xf - -C "$scratch"
tests='"tests/pipeline/test_validate.py", "tests/pipeline/test_assembly.py", "tests/pipeline/test_transcript.py", "tests/interfaces/test_periodic.py"'
cat >> "$scratch/pyproject.toml" <<TOML

[tool.mutmut]
source_paths = ["speech_event/"]
only_mutate = ["speech_event/pipeline/validate.py", "speech_event/pipeline/assembly.py", "speech_event/pipeline/transcript.py", "speech_event/interfaces/periodic.py"]
also_copy = ["fixtures/", "harness/"]
pytest_add_cli_args = ["-p", "no:cacheprovider", "-q"]
pytest_add_cli_args_test_selection = [$tests]
TOML
cd "$scratch"
XDG_CACHE_HOME="$scratch/cache" "$mutmut" run --max-children 2 > mutmut.log 2>&1
"$mutmut" results --all true 2>/dev/null | "$python" "$checkout/bench/tools/mutation_report.py"
echo "survivors:"
"$mutmut" results 2>/dev/null

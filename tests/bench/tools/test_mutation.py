"""bench/tools/mutation.sh's report, run by the script itself on the README's python3, with a stand-in
for mutmut that answers with results the test makes up (a real mutation run takes minutes)."""

import os
import subprocess
from pathlib import Path

from bench.tools.mutation_report import report
from fixtures.paths import ROOT

# mutmut 3 as the script calls it: run, then results with --all true (every mutant) and without
# (the survivors); its mutants of methods are named with 'ǁ', as mutmut names them.
FAKE_MUTMUT = """#!/bin/sh
case "$*" in
    "run --max-children 2") echo "mutants checked" ;;
    "results --all true") cat <<'EOF'
    speech_event.interfaces.periodic.xǁPeriodicǁstart__mutmut_1: killed
    speech_event.interfaces.periodic.xǁPeriodicǁstart__mutmut_2: survived
    speech_event.pipeline.validate.x_validate__mutmut_1: killed
    speech_event.pipeline.validate.x_validate__mutmut_2: killed
    speech_event.pipeline.validate.x_validate__mutmut_3: timeout
EOF
    ;;
    "results") echo "    speech_event.interfaces.periodic.xǁPeriodicǁstart__mutmut_2: survived" ;;
    *) echo "unexpected: mutmut $*" >&2; exit 2 ;;
esac
"""


def test_the_mutation_script_prints_each_modules_score_the_overall_score_and_the_survivors(
    tmp_path: Path,
) -> None:
    # The script runs the mutmut beside the Python it is given: python3's own binary, linked here.
    python3 = subprocess.run(
        ["python3", "-c", "import sys; print(sys.executable)"], capture_output=True, text=True, check=True
    ).stdout.strip()
    (tmp_path / "python3").symlink_to(os.path.realpath(python3))
    mutmut = tmp_path / "mutmut"
    mutmut.write_text(FAKE_MUTMUT, encoding="utf-8")
    mutmut.chmod(0o755)
    result = subprocess.run(
        ["bash", str(ROOT / "bench" / "tools" / "mutation.sh"), str(tmp_path / "python3")],
        capture_output=True,
        text=True,
        encoding="utf-8",
    )
    assert result.stderr == ""
    assert result.stdout == (
        "speech_event.interfaces.periodic: 1/2 killed {'killed': 1, 'survived': 1}\n"
        "speech_event.pipeline.validate: 2/3 killed {'killed': 2, 'timeout': 1}\n"
        "overall: 3/5 = 60.0 %\n"
        "survivors:\n"
        "    speech_event.interfaces.periodic.xǁPeriodicǁstart__mutmut_2: survived\n"
    )
    assert result.returncode == 0


def test_results_without_mutants_are_reported_as_such() -> None:
    assert report(["", "2 mutants checked"]) == ["overall: no mutants in mutmut's results"]

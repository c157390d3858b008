"""bench/tools/mutation.sh's report: mutmut 3's ``results --all true`` lines on standard input, each
``    module.function__mutmut_N: status``; prints killed/total per module, then overall.

A file of its own, not inline in the script, so ruff and mypy read it (its inline predecessor was
a SyntaxError that nothing checked). Standard library only: it runs on any python3 from 3.8.
"""

import collections
import sys
from typing import Counter, Dict, Iterable, List


def report(lines: Iterable[str]) -> List[str]:
    """The report's lines for mutmut's result lines (others, such as blank ones, are skipped)."""
    counts: Dict[str, Counter[str]] = collections.defaultdict(collections.Counter)
    for line in lines:
        name, _, status = line.strip().rpartition(":")
        parts = name.split(".")
        mutant = next((index for index, part in enumerate(parts) if "__mutmut_" in part), None)
        if mutant is not None:
            counts[".".join(parts[:mutant])][status.strip()] += 1
    printed = []
    killed = total = 0
    for module, count in sorted(counts.items()):
        killed, total = killed + count["killed"], total + sum(count.values())
        printed.append(f"{module}: {count['killed']}/{sum(count.values())} killed {dict(count)}")
    if total == 0:
        printed.append("overall: no mutants in mutmut's results")  # not a ZeroDivisionError
    else:
        printed.append(f"overall: {killed}/{total} = {100 * killed / total:.1f} %")
    return printed


def main() -> None:
    """Read mutmut's results on standard input, print the report."""
    for line in report(sys.stdin):
        print(line)


if __name__ == "__main__":
    main()

"""Which Debian package owns a file, and whether the project's install step names it.

CI on a used machine once passed because two packages had been installed by hand; a new machine
failed. So every Debian file that the ROS build and tests read must belong to a package of
tests/debian/*.txt or to one apt installs with them (Depends and Pre-Depends, not Recommends).
"""

import os
import re
import subprocess
from functools import lru_cache
from pathlib import Path
from typing import Dict, FrozenSet, Iterable, List

LISTS = Path(__file__).resolve().parents[1] / "debian"


def listed(path: Path) -> List[str]:
    """The packages of one list file: a name a line, '#' comments."""
    return [name for line in path.read_text().splitlines() for name in line.split("#")[0].split()[:1]]


def named_packages() -> List[str]:
    """Every package the install steps name (tests/debian/*.txt)."""
    return [name for path in sorted(LISTS.glob("*.txt")) for name in listed(path)]


@lru_cache(maxsize=1)
def installable() -> FrozenSet[str]:
    """The named packages and everything apt installs with them."""
    listing = subprocess.run(
        [
            "apt-cache",
            "depends",
            "--recurse",
            "--installed",
            "--no-recommends",
            "--no-suggests",
            "--no-conflicts",
            "--no-breaks",
            "--no-replaces",
            "--no-enhances",
            *named_packages(),
        ],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    return frozenset(
        line.split(":")[0] for line in listing.splitlines() if line and not line.startswith((" ", "<"))
    )


def _usr_merged_twin(path: str) -> str:
    """/usr/sbin/ip is dpkg's /sbin/ip: with /usr merged, /bin, /sbin and /lib are links into /usr."""
    for top in ("/bin/", "/sbin/", "/lib/"):
        if path.startswith("/usr" + top):
            return path[len("/usr") :]
    return path


def owners(paths: Iterable[str]) -> Dict[str, str]:
    """The package that owns each path (symbolic links followed), or '' for none."""
    real = {path: os.path.realpath(path) for path in paths}
    asked = sorted({twin for target in real.values() for twin in (target, _usr_merged_twin(target))})
    found = subprocess.run(["dpkg", "-S", *asked], capture_output=True, text=True).stdout
    owner: Dict[str, str] = {}
    for line in found.splitlines():
        match = re.match(r"^([^:,\s]+)(?::\w+)?(?:, [^:]+)?: (/.*)$", line)
        if match and not line.startswith("diversion"):
            owner.setdefault(match.group(2), match.group(1))
    return {
        path: owner.get(target) or owner.get(_usr_merged_twin(target), "") for path, target in real.items()
    }


def not_installed_by_the_project(paths: Iterable[str]) -> Dict[str, str]:
    """Each path whose package no install step brings, with that package ('' for a file of none)."""
    return {path: package for path, package in owners(paths).items() if package not in installable()}

"""Every Debian file the ROS build and tests read comes from a package the install step names
(issue 17, item 3): a package installed by hand can no longer hide a gap."""

import shutil
import subprocess
import sys
from pathlib import Path
from typing import List

from fixtures.debian_packages import LISTS, listed, named_packages, not_installed_by_the_project
from fixtures.paths import ROOT
from speech_event.adapters import ros_interfaces

# What the suite runs: roscore and roslaunch, catkin, the rosservice/rostopic commands, the X
# server and screenshot tools of the window test, ip for the network namespaces.
COMMANDS = (
    "roscore",
    "rosmaster",
    "roslaunch",
    "rosservice",
    "rostopic",
    "catkin_make",
    "Xvfb",
    "import",
    "ip",
)
# Every module of ours that ROS or Tk can reach, imported in a fresh interpreter.
IMPORTED = (
    "speech_event.adapters.ros",
    "speech_event.gui",
    "harness.ros.runner",
    "harness.ros.stand_in",
    "harness.ros.checker",
    "harness.driver_node",
    "harness.ros.driver_side",
    "tests.ros.conftest",
    "fixtures.two_hosts",
)


def _system_modules() -> List[str]:
    code = (
        "import importlib, sys\n"
        f"for name in {IMPORTED!r}: importlib.import_module(name)\n"
        "print('\\n'.join(sorted({m.__file__ for m in list(sys.modules.values())"
        " if getattr(m, '__file__', None) and m.__file__.startswith('/usr/')})))\n"
    )
    return subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()


def _message_definitions() -> List[str]:
    files = [str(ros_interfaces.GENACTION)]
    for package in ros_interfaces.DEPENDENCIES:
        files += [str(path) for path in sorted(Path(ros_interfaces.message_directory(package)).glob("*.msg"))]
    return files


def test_the_interface_build_reads_only_files_of_named_packages() -> None:
    files = _message_definitions()
    assert len(files) > 20  # std_msgs' and actionlib_msgs' definitions, and genaction.py
    assert not_installed_by_the_project(files) == {}


def test_the_python_modules_from_debian_come_from_named_packages() -> None:
    modules = _system_modules()
    assert any(path.startswith("/usr/lib/python3/dist-packages/rospy/") for path in modules)
    assert not_installed_by_the_project(modules) == {}


def test_the_commands_the_suite_runs_come_from_named_packages() -> None:
    found = {command: shutil.which(command) for command in COMMANDS}
    assert [command for command, path in found.items() if path is None] == []
    assert not_installed_by_the_project(path for path in found.values() if path) == {}


def test_the_readme_installs_exactly_the_ros_list() -> None:
    readme = (ROOT / "README.md").read_text()
    line = readme.split("sudo apt-get install -y ", 1)[1].split("\n    /usr/bin/python3", 1)[0]
    expected = listed(LISTS / "ros.txt")
    assert line.replace("\\", " ").split() == expected
    assert set(expected) <= set(named_packages())

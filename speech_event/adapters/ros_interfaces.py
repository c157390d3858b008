"""Builds the Python classes of the node's ROS interfaces (msg/, srv/, action/) with Debian's genpy.

The definitions ship inside the package (``speech_event/definitions/{msg,srv,action}``), so a wheel
or sdist install has them too. On the robot catkin builds them (CMakeLists.txt: add_message_files,
add_service_files, add_action_files); elsewhere this is the build step, no catkin workspace needed:
``python -m speech_event.adapters.ros_interfaces`` writes ``speech_event/msg`` and
``speech_event/srv`` next to the code, where catkin's install puts them too. The ROS adapter runs
it on import when they are missing or older than their definitions. Where the package's folder
cannot be written (a system-wide install run by another user) they are built under
``$XDG_CACHE_HOME/speech_event/ros_interfaces/<digest of the definitions>`` and found there by an
import finder of this module's (the package itself is not touched). Actions go through
actionlib_msgs' own genaction.py (Debian's libactionlib-msgs-dev) into the seven messages of an
action, as catkin does.

``generate`` also builds any other package's definitions: the tests build the robot's own client
types (other names, same fields) this way and call the node through them.
"""

import fcntl
import hashlib
import importlib.abc
import importlib.machinery
import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Dict, List, Optional, Sequence

PACKAGE = "speech_event"
PACKAGE_DIRECTORY = Path(__file__).resolve().parents[1]  # speech_event/: its msg/ and srv/ subpackages
DEFINITIONS = PACKAGE_DIRECTORY / "definitions"  # srv/ and action/, named in CMakeLists.txt too
GENACTION = Path("/usr/lib/actionlib_msgs/genaction.py")
DEPENDENCIES = ("std_msgs", "actionlib_msgs")


class InterfaceError(Exception):
    """The interfaces cannot be built; the message says what is missing."""


def message_directory(package: str) -> str:
    """The folder of a ROS package's .msg files (a Debian ros-* package's), or InterfaceError."""
    import rospkg

    try:
        return str(Path(rospkg.RosPack().get_path(package)) / "msg")
    except rospkg.ResourceNotFound:
        raise InterfaceError(
            f"ROS package {package} not found: apt-get install ros-{package.replace('_', '-')}"
        ) from None


def _action_messages(action: Path, out: Path) -> List[Path]:
    if not GENACTION.is_file():
        raise InterfaceError(f"{GENACTION} not found: apt-get install libactionlib-msgs-dev")
    before = set(out.glob("*.msg"))
    subprocess.run(
        [sys.executable, str(GENACTION), str(action), "-o", str(out)], check=True, capture_output=True
    )
    return sorted(set(out.glob("*.msg")) - before)


def generate(package: str, definitions: Path, out: Path) -> None:
    """Python classes for ``definitions``/{msg,srv,action} as package ``package``, in ``out``/{msg,srv}."""
    from genpy.generate_initpy import write_modules
    from genpy.generator import MsgGenerator, SrvGenerator

    with tempfile.TemporaryDirectory(prefix="ros_interfaces_") as work:
        messages = Path(work) / "definitions"
        messages.mkdir()
        for own in sorted((definitions / "msg").glob("*.msg")):
            shutil.copy(own, messages)
        for action in sorted((definitions / "action").glob("*.action")):
            _action_messages(action, messages)
        search: Dict[str, List[str]] = {package: [str(messages)]}
        search.update({dependency: [message_directory(dependency)] for dependency in DEPENDENCIES})
        built = Path(work) / "built"
        for kind, generator, files in (
            ("msg", MsgGenerator(), sorted(messages.glob("*.msg"))),
            ("srv", SrvGenerator(), sorted((definitions / "srv").glob("*.srv"))),
        ):
            if not files:
                continue
            target = built / kind
            if generator.generate_messages(package, [str(f) for f in files], str(target), search):
                raise InterfaceError(f"genpy could not build the {kind} classes of {package}")
            write_modules(str(target))
        for kind in ("msg", "srv"):
            if (built / kind).is_dir():
                shutil.rmtree(out / kind, ignore_errors=True)
                (built / kind).rename(out / kind)


def _definitions() -> List[Path]:
    kinds = (("msg", "*.msg"), ("srv", "*.srv"), ("action", "*.action"))
    return sorted(path for kind, pattern in kinds for path in (DEFINITIONS / kind).glob(pattern))


def output_directory(writable: bool) -> Path:
    """Where the classes go: the package's own folder, or (not ``writable``) a cache of the user's."""
    if writable:
        return PACKAGE_DIRECTORY
    digest = hashlib.sha1(b"".join(path.read_bytes() for path in _definitions())).hexdigest()[:16]
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return cache / "speech_event" / "ros_interfaces" / digest


def _up_to_date(out: Path) -> bool:
    built = [out / "msg" / "__init__.py", out / "srv" / "__init__.py"]
    if not all(path.is_file() for path in built):
        return False
    newest = max((path.stat().st_mtime for path in _definitions()), default=0.0)
    return min(path.stat().st_mtime for path in built) >= newest


class _InterfacesFinder(importlib.abc.MetaPathFinder):
    """Imports ``speech_event.msg`` and ``speech_event.srv`` from a folder outside the package;
    their modules then come from there, as a subpackage's do."""

    def __init__(self, out: Path) -> None:
        self.out = out

    def find_spec(
        self, fullname: str, path: Optional[Sequence[str]], target: object = None
    ) -> Optional[importlib.machinery.ModuleSpec]:
        package, _, subpackage = fullname.rpartition(".")
        init = self.out / subpackage / "__init__.py"
        if package != PACKAGE or subpackage not in ("msg", "srv") or not init.is_file():
            return None
        return importlib.util.spec_from_file_location(
            fullname, init, submodule_search_locations=[str(init.parent)]
        )


def ensure_built(writable: Optional[bool] = None) -> Path:
    """Build the node's interfaces unless catkin or an earlier run did (one process at a time).

    ``writable`` (default: whether the package's folder is) chooses output_directory; outside the
    package, an _InterfacesFinder finds ``speech_event.msg`` and ``speech_event.srv`` there."""
    out = output_directory(os.access(PACKAGE_DIRECTORY, os.W_OK) if writable is None else writable)
    if out != PACKAGE_DIRECTORY:
        out.mkdir(parents=True, exist_ok=True)
        if not any(isinstance(finder, _InterfacesFinder) and finder.out == out for finder in sys.meta_path):
            sys.meta_path.insert(0, _InterfacesFinder(out))
    if not _up_to_date(out):
        with open(out / ".ros_interfaces.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not _up_to_date(out):
                generate(PACKAGE, DEFINITIONS, out)
    return out


def main() -> int:
    """The build step, ``python -m speech_event.adapters.ros_interfaces``; exit status 2 if it cannot."""
    out = output_directory(os.access(PACKAGE_DIRECTORY, os.W_OK))
    try:
        out.mkdir(parents=True, exist_ok=True)
        generate(PACKAGE, DEFINITIONS, out)
    except (InterfaceError, ImportError, subprocess.CalledProcessError) as problem:
        print(f"error: cannot build the ROS interfaces: {problem}", file=sys.stderr)
        return 2
    print(f"built {out / 'msg'} and {out / 'srv'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

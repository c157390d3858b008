"""The architecture, read from the code's import statements with ast (nothing is imported): the
node library's layers import only downwards, the shared ONNX code knows no family, no modules
import each other, and ROS stays in its rooms.

Every import counts, at the top of a module or inside a function or ``if TYPE_CHECKING``: an
import put inside a function to dodge a circle is still a circle."""

import ast
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, Iterator, List, Set

from fixtures.paths import ROOT

PACKAGES = ("speech_event", "harness", "fixtures", "bench")
SHARED_ONNX = "speech_event.recognizers.onnx"
RECOGNIZERS = "speech_event.recognizers"
# The ROS 1 client libraries and message packages, and where they may be imported: the adapters
# (speech_event/adapters/ros*.py), the harness's ROS side (harness/ros/) and the benchmarks that
# measure the node on a roscore (bench/figures/ros*.py).
ROS = (
    "rospy",
    "actionlib",
    "actionlib_msgs",
    "diagnostic_msgs",
    "genpy",
    "rosgraph",
    "rosgraph_msgs",
    "rospkg",
    "std_msgs",
)
ROS_ROOMS = (
    "speech_event.adapters.ros",
    "harness.ros",
    "fixtures.ros",
    "fixtures.text_listener",
    "bench.figures.ros",
)
# The node library's layers, lowest first: a module imports from its own layer or those below it.
# The base (the ports, the configuration, messages and grammars) knows no engine; the engines know
# no node; the robot's interfaces know no pipeline; the pipeline, message in to text out, knows no
# turn rules; the rules on the utterance being collected know no node; the node is the wiring, and
# the deployment, the GUI and the public API sit on top.
LAYERS = (
    (
        "speech_event.errors",
        "speech_event.keyvalue",
        "speech_event.config",
        "speech_event.grammar",
        "speech_event.messages",
        "speech_event.ports",
        "speech_event.topics",
        "speech_event.spelling",
    ),
    ("speech_event.recognizers",),
    ("speech_event.exporters",),
    ("speech_event.models",),
    ("speech_event.interfaces",),
    ("speech_event.pipeline",),
    ("speech_event.turns",),
    ("speech_event.node", "speech_event.adapters"),
    ("speech_event.application", "speech_event.gui"),
    ("speech_event", "speech_event.__main__"),
)


@dataclass(frozen=True)
class Import:
    """One name an import statement of ``module`` names: ``from a.b import c`` names ``a.b.c``."""

    module: str
    line: int
    name: str

    def within(self, package: str) -> bool:
        return self.name == package or self.name.startswith(package + ".")


# genpy's output, written into the checkout where the ROS interfaces are built for an editable install
# (speech_event/adapters/ros_interfaces.py): not the project's code, as for ruff and mypy.
GENERATED = ("speech_event/msg", "speech_event/srv")


def _modules() -> Dict[str, Path]:
    """Every module of PACKAGES by dotted name (a package by its own name)."""
    modules: Dict[str, Path] = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            if path.relative_to(ROOT).as_posix().startswith(GENERATED):
                continue
            parts = path.relative_to(ROOT).with_suffix("").parts
            modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return modules


MODULES = _modules()


def _imports(module: str, path: Path) -> Iterator[Import]:
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield Import(module, node.lineno, alias.name)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: from the package, or level - 1 packages above it
                above = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join(above + ([base] if base else []))
            for alias in node.names:
                yield Import(module, node.lineno, f"{base}.{alias.name}")


IMPORTS = [found for module, path in MODULES.items() for found in _imports(module, path)]


def _module_of(name: str) -> str:
    """The module of ours that an imported name is or lies in; "" for none of ours."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name


def _circles(graph: Dict[str, Set[str]]) -> List[List[str]]:
    """The groups of modules that import each other, directly or around a circle (Tarjan's
    strongly connected components of more than one module)."""
    order: Dict[str, int] = {}
    low: Dict[str, int] = {}
    stack: List[str] = []
    circles: List[List[str]] = []

    def visit(module: str) -> None:
        order[module] = low[module] = len(order)
        stack.append(module)
        for other in sorted(graph[module]):
            if other not in order:
                visit(other)
                low[module] = min(low[module], low[other])
            elif other in stack:
                low[module] = min(low[module], order[other])
        if low[module] == order[module]:
            group = stack[stack.index(module) :]
            del stack[stack.index(module) :]
            if len(group) > 1:
                circles.append(sorted(group))

    for module in sorted(graph):
        if module not in order:
            visit(module)
    return circles


def test_the_modules_are_found_and_their_imports_read() -> None:
    assert {"speech_event", "speech_event.node", "harness.ros.runner", "bench.figures.asr"} <= set(MODULES)
    read = {(found.module, found.name) for found in IMPORTS}
    assert ("speech_event.node", "speech_event.config.SpeechEventConfig") in read
    assert ("harness.driver_node", "harness.ros.driver_side.ros_side") in read  # inside a function


def _in_library(module: str) -> bool:
    return module == "speech_event" or module.startswith("speech_event.")


def _layer(module: str) -> int:
    """The layer of a module of speech_event: the longest prefix in LAYERS names it."""
    matches = [
        (len(prefix), index)
        for index, prefixes in enumerate(LAYERS)
        for prefix in prefixes
        if module == prefix or module.startswith(prefix + ".")
    ]
    return max(matches)[1]


LIBRARY_IMPORTS = [
    (found, _module_of(found.name))
    for found in IMPORTS
    if _in_library(found.module) and _in_library(_module_of(found.name))
]


def test_every_module_of_the_node_library_has_its_layer() -> None:
    """A new module is placed in LAYERS, or it would sit on top with the public API."""
    top = len(LAYERS) - 1
    unplaced = [
        module
        for module in MODULES
        if _in_library(module) and _layer(module) == top and module not in LAYERS[top]
    ]
    assert unplaced == []


def test_the_node_library_imports_only_downwards() -> None:
    upwards = [
        f"{found.module}:{found.line} imports {found.name}"
        for found, target in LIBRARY_IMPORTS
        if _layer(target) > _layer(found.module)
    ]
    assert upwards == []


def test_the_layers_tell_upwards_from_downwards() -> None:
    assert _layer("speech_event.pipeline.storage") > _layer("speech_event.interfaces.health")
    assert _layer("speech_event.turns.rules") > _layer("speech_event.pipeline.worker")
    assert _layer("speech_event.recognizers.onnx.grammar_choice") == _layer("speech_event.recognizers")
    assert _layer("speech_event.node") > _layer("speech_event.turns") > _layer("speech_event.ports")


def test_the_node_library_imports_nothing_of_the_harness_the_benchmarks_or_the_tests() -> None:
    wrong = [
        f"{found.module}:{found.line} imports {found.name}"
        for found in IMPORTS
        if _in_library(found.module)
        and any(found.within(outside) for outside in ("harness", "bench", "fixtures", "tests"))
    ]
    assert wrong == []


def test_the_shared_onnx_code_imports_nothing_of_the_recognizers_but_itself() -> None:
    """A new family registers itself (onnx/families.py); the shared code never names one."""
    wrong = [
        f"{found.module}:{found.line} imports {found.name}"
        for found in IMPORTS
        if found.module.startswith(SHARED_ONNX)
        and found.within(RECOGNIZERS)
        and not found.within(SHARED_ONNX)
    ]
    assert wrong == []


def test_no_modules_import_each_other() -> None:
    graph: Dict[str, Set[str]] = {module: set() for module in MODULES}
    for found in IMPORTS:
        target = _module_of(found.name)
        if target and target != found.module:
            graph[found.module].add(target)
    assert _circles(graph) == []


def test_no_module_imports_another_modules_private_names() -> None:
    """What two modules share is public in the one that owns it (or in a module of its own)."""
    wrong = [
        f"{found.module}:{found.line} imports {found.name}"
        for found in IMPORTS
        if _module_of(found.name) not in ("", found.module)
        and found.name.rpartition(".")[2].startswith("_")
        and not found.name.rpartition(".")[2].startswith("__")
    ]
    assert wrong == []


def test_a_circle_is_found_however_long() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"d"}, "f": {"g"}, "g": {"f"}}
    assert _circles(graph) == [["a", "b", "c"], ["f", "g"]]


def test_ros_is_imported_only_in_its_rooms() -> None:
    wrong = [
        f"{found.module}:{found.line} imports {found.name}"
        for found in IMPORTS
        if any(found.within(library) for library in ROS) and not found.module.startswith(ROS_ROOMS)
    ]
    assert wrong == []

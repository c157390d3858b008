"""ONNX files written with their weights in a file beside them (``encoder.onnx.data``).

onnxruntime then reads the weights from there instead of from the whole file parsed as one protobuf
message, which it held beside the weights while loading: Whisper base's fp32 decoder peaked at 446
MiB loading, 343 with its weights beside; after loading it held 345 and 242, the weights it only
gathers from being mapped rather than read. And an ONNX file, one protobuf message, cannot pass 2
GiB (Whisper large's fp32 graphs are about 3 GB each).
"""

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # onnx comes with the export and pull extras, imported where it is used
    import onnx

EXTERNAL_DATA_SUFFIX = ".data"


def save_graph(model: "onnx.ModelProto", path: Path, data_name: str = "") -> None:
    """``model`` to ``path``, its weights in ``data_name`` beside it (``path``.data when not
    named), which onnxruntime reads given the graph's path."""
    import onnx

    data = path.with_name(data_name or path.name + EXTERNAL_DATA_SUFFIX)
    onnx.save(model, str(path), save_as_external_data=True, all_tensors_to_one_file=True, location=data.name)
    # onnx creates the weights' file readable by its owner alone; whoever may read the graph (the
    # node's user on the robot) must read its weights too
    data.chmod(path.stat().st_mode & 0o777)


def has_weights_beside(path: Path) -> bool:
    """Whether the graph at ``path`` keeps weights in a file beside it."""
    import onnx

    graph = onnx.load(str(path), load_external_data=False).graph
    return any(tensor.data_location == onnx.TensorProto.EXTERNAL for tensor in graph.initializer)


def remove_graph(path: Path) -> None:
    """``path`` and the weights beside it, those that are there."""
    for file in (path, path.with_name(path.name + EXTERNAL_DATA_SUFFIX)):
        if file.exists():
            file.unlink()

"""CTranslate2's model.bin, read with numpy alone (no ctranslate2): the file of a faster-whisper model.

The layout, as CTranslate2's model_spec.py writes it and its model.cc reads it (little-endian):
the binary version (uint32), the spec's name (a string: uint16 length counting a closing NUL,
the UTF-8 bytes, the NUL) and its revision (uint32); the number of variables (uint32), then each
variable: its name, its rank (uint8), each dimension (uint32), its data type (uint8: 0 float32,
1 int8, 2 int16, 3 int32, 4 float16, 5 bfloat16), its size in bytes (uint32) and the bytes; then
the number of aliases (uint32) and each alias: its name and the variable it stands for (a tied
weight is stored once). Binary versions 4 to 6 have this layout (older ones gave an item size, not
a type).

Quantized weights (int8: a scale per row, int16: one scale) come with ``NAME_scale``, by which
CTranslate2 multiplied the weight before rounding it: ``float32`` divides it back out.
"""

import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Tuple

import numpy as np

from speech_event.errors import ModelError

BINARY_VERSIONS = (4, 5, 6)
# CTranslate2's DataType ids; bfloat16, which numpy lacks, is read as its 16 bits.
DTYPES = ("float32", "int8", "int16", "int32", "float16", "bfloat16")
_NUMPY: Dict[str, np.dtype] = {
    "float32": np.dtype("<f4"),
    "int8": np.dtype("i1"),
    "int16": np.dtype("<i2"),
    "int32": np.dtype("<i4"),
    "float16": np.dtype("<f2"),
    "bfloat16": np.dtype("<u2"),
}
SCALE_SUFFIX = "_scale"


@dataclass(frozen=True)
class Variable:
    """One variable as stored: its values in its own data type (bfloat16 as its 16 bits)."""

    name: str
    dtype: str
    values: np.ndarray


@dataclass(frozen=True)
class ModelBin:
    """A model.bin: its header, its variables by name and its aliases (alias -> variable)."""

    path: Path
    version: int
    spec: str
    revision: int
    variables: Dict[str, Variable]
    aliases: Dict[str, str]

    def variable(self, name: str) -> Variable:
        """The variable ``name`` or the one it is an alias of; ModelError when there is none."""
        found = self.variables.get(self.aliases.get(name, name))
        if found is None:
            raise ModelError(f"{self.path}: no variable {name} in this {self.spec} model")
        return found

    def float32(self, name: str) -> np.ndarray:
        """Variable ``name``'s values as float32: converted, or for an integer weight divided by its
        ``_scale`` (per row, or one for all), as CTranslate2 dequantizes it."""
        variable = self.variable(name)
        values = variable.values
        if variable.dtype in ("float32", "float16"):
            return values.astype(np.float32)
        if variable.dtype == "bfloat16":  # the high half of a float32
            return (values.astype(np.uint32) << 16).view(np.float32)
        scale_name = self.aliases.get(name, name) + SCALE_SUFFIX
        if scale_name not in self.variables:
            raise ModelError(
                f"{self.path}: variable {name} is {variable.dtype} without {scale_name}; a weight is "
                "float32, float16 or bfloat16, or int8 or int16 with its scale"
            )
        scale = self.float32(scale_name)
        if scale.size not in (1, values.shape[0]):
            raise ModelError(
                f"{self.path}: {scale_name} has {scale.size} values for {name} of shape "
                f"{list(values.shape)}: one, or one per row ({values.shape[0]})"
            )
        rows = scale.reshape((-1,) + (1,) * (values.ndim - 1))
        dequantized: np.ndarray = values.astype(np.float32) / rows
        return dequantized

    def integer(self, name: str) -> int:
        """A scalar integer variable (a count, such as num_heads)."""
        variable = self.variable(name)
        if variable.dtype not in ("int8", "int16", "int32") or variable.values.size != 1:
            raise ModelError(
                f"{self.path}: variable {name} is {variable.dtype} of shape {list(variable.values.shape)}; "
                "a single integer expected"
            )
        return int(variable.values.reshape(()))


class _Cursor:
    """Reads model.bin's fields in order; a field past the end is a ModelError naming it."""

    def __init__(self, path: Path, data: bytes) -> None:
        self.path = path
        self.data = memoryview(data)  # slices of it share the file's bytes: no copy of the weights
        self.offset = 0

    def take(self, size: int, what: str) -> memoryview:
        end = self.offset + size
        if end > len(self.data):
            raise ModelError(
                f"{self.path}: ends inside {what} (byte {self.offset} of {len(self.data)}): "
                "a truncated or not a CTranslate2 model.bin"
            )
        piece = self.data[self.offset : end]
        self.offset = end
        return piece

    def number(self, code: str, what: str) -> int:
        value: int = struct.unpack_from("<" + code, self.take(struct.calcsize(code), what))[0]
        return value

    def string(self, what: str) -> str:
        size = self.number("H", what)
        raw = self.take(size, what)
        if size == 0 or raw[-1] != 0:
            raise ModelError(f"{self.path}: {what} at byte {self.offset - size} does not end in a NUL byte")
        try:
            return bytes(raw[:-1]).decode("utf-8")
        except UnicodeDecodeError:
            raise ModelError(f"{self.path}: {what} at byte {self.offset - size} is not UTF-8") from None


def _variable(cursor: _Cursor, index: int) -> Variable:
    name = cursor.string(f"the name of variable {index}")
    rank = cursor.number("B", f"the rank of {name}")
    shape = tuple(cursor.number("I", f"the shape of {name}") for _ in range(rank))
    type_id = cursor.number("B", f"the data type of {name}")
    if type_id >= len(DTYPES):
        known = ", ".join(f"{number} {dtype}" for number, dtype in enumerate(DTYPES))
        raise ModelError(f"{cursor.path}: variable {name} has data type {type_id}; CTranslate2's are {known}")
    dtype = DTYPES[type_id]
    size = cursor.number("I", f"the size of {name}")
    expected = int(np.prod(shape, dtype=np.int64)) * _NUMPY[dtype].itemsize
    if size != expected:
        raise ModelError(
            f"{cursor.path}: variable {name} holds {size} bytes; its shape {list(shape)} of {dtype} "
            f"takes {expected}"
        )
    values = np.frombuffer(cursor.take(size, f"the values of {name}"), dtype=_NUMPY[dtype]).reshape(shape)
    return Variable(name, dtype, values)


def read_model_bin(path: Path) -> ModelBin:
    """Read a CTranslate2 model.bin; ModelError names the file and what in it cannot be read."""
    try:
        data = path.read_bytes()
    except OSError as problem:
        raise ModelError(f"{path}: cannot read it: {problem.strerror}") from None
    cursor = _Cursor(path, data)
    version = cursor.number("I", "the binary version")
    if version not in BINARY_VERSIONS:
        raise ModelError(
            f"{path}: binary version {version}; CTranslate2's model.bin of versions "
            f"{BINARY_VERSIONS[0]} to {BINARY_VERSIONS[-1]} can be read (convert the model again with "
            "a recent CTranslate2)"
        )
    spec = cursor.string("the spec's name")
    revision = cursor.number("I", "the spec's revision")
    variables: List[Variable] = [
        _variable(cursor, index) for index in range(cursor.number("I", "the variables"))
    ]
    aliases: List[Tuple[str, str]] = []
    for index in range(cursor.number("I", "the aliases")):
        alias = cursor.string(f"alias {index}")
        aliases.append((alias, cursor.string(f"the variable of alias {alias}")))
    if cursor.offset != len(data):
        raise ModelError(
            f"{path}: {len(data) - cursor.offset} bytes after its last alias: not one whole "
            "CTranslate2 model.bin"
        )
    by_name = {variable.name: variable for variable in variables}
    for alias, target in aliases:
        if target not in by_name:
            raise ModelError(f"{path}: alias {alias} stands for {target}, which is no variable of the file")
    return ModelBin(path, version, spec, revision, by_name, dict(aliases))

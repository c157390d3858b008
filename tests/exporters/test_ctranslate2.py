"""The model.bin reader (speech_event/exporters/ctranslate2.py) on files written by hand as
CTranslate2 writes them (fixtures/ct2_whisper_model.py): every data type read back, quantized
weights dequantized as CTranslate2 does, aliases, and each malformed file's message."""

import struct
from pathlib import Path
from typing import List, Sequence, Tuple

import numpy as np
import pytest

from fixtures.ct2_whisper_model import (
    Stored,
    bfloat16_bits,
    model_bin_bytes,
    stored_as,
    variable_bytes,
)
from speech_event.errors import ModelError
from speech_event.exporters.ctranslate2 import ModelBin, read_model_bin

VALUES = np.array([[0.5, -1.25, 3.0], [0.0, 0.0, 0.0], [-2.0, 0.75, 0.125]], np.float32)


def _write(tmp_path: Path, data: bytes) -> Path:
    path = tmp_path / "model.bin"
    path.write_bytes(data)
    return path


def _read(tmp_path: Path, variables: List[Stored], aliases: Sequence[Tuple[str, str]] = ()) -> ModelBin:
    return read_model_bin(_write(tmp_path, model_bin_bytes(variables, aliases)))


def test_the_header_variables_and_aliases_are_read_as_written(tmp_path: Path) -> None:
    model = _read(
        tmp_path,
        [("a/weight", "float32", VALUES), ("a/num_heads", "int16", np.array(6, np.int16))],
        [("b/weight", "a/weight")],
    )
    assert (model.version, model.spec, model.revision) == (6, "WhisperSpec", 3)
    assert list(model.variables) == ["a/weight", "a/num_heads"]
    assert model.aliases == {"b/weight": "a/weight"}
    np.testing.assert_array_equal(model.float32("b/weight"), VALUES)
    assert model.integer("a/num_heads") == 6


@pytest.mark.parametrize("dtype", ["float32", "float16", "bfloat16"])
def test_float_variables_of_each_type_read_as_float32(tmp_path: Path, dtype: str) -> None:
    # every value here is exact in float16 and bfloat16
    model = _read(tmp_path, stored_as("w", VALUES, dtype))
    assert model.variables["w"].dtype == dtype
    read = model.float32("w")
    assert read.dtype == np.float32
    np.testing.assert_array_equal(read, VALUES)


def test_bfloat16_is_the_high_half_of_float32(tmp_path: Path) -> None:
    values = np.array([1.0 / 3.0, -1e30, 6.5e-3], np.float32)
    model = _read(tmp_path, [("w", "bfloat16", bfloat16_bits(values))])
    expected = (bfloat16_bits(values).astype(np.uint32) << 16).view(np.float32)
    np.testing.assert_array_equal(model.float32("w"), expected)
    np.testing.assert_allclose(model.float32("w"), values, rtol=2**-8)


def test_int8_weights_are_divided_by_their_scale_per_row(tmp_path: Path) -> None:
    stored = stored_as("w", VALUES, "int8")
    model = _read(tmp_path, stored)
    quantized, scale = stored[0][2], stored[1][2]
    np.testing.assert_array_equal(model.float32("w"), quantized.astype(np.float32) / scale[:, None])
    # 127 levels over each row's largest magnitude; the zero row stays zero
    np.testing.assert_allclose(model.float32("w"), VALUES, atol=3.0 / 127 / 2 + 1e-7)


def test_a_convolutions_int8_weight_has_a_scale_per_output_channel(tmp_path: Path) -> None:
    kernel = np.arange(24, dtype=np.float32).reshape(2, 4, 3) - 11.5
    stored = stored_as("conv/weight", kernel, "int8")
    assert stored[1][2].shape == (2,)
    model = _read(tmp_path, stored)
    np.testing.assert_allclose(model.float32("conv/weight"), kernel, atol=11.5 / 127 / 2 + 1e-6)


def test_int16_weights_have_one_scale(tmp_path: Path) -> None:
    stored = stored_as("w", VALUES, "int16")
    model = _read(tmp_path, stored)
    np.testing.assert_array_equal(model.float32("w"), stored[0][2].astype(np.float32) / stored[1][2])


def test_an_alias_of_a_quantized_weight_uses_that_weights_scale(tmp_path: Path) -> None:
    model = _read(
        tmp_path, stored_as("embeddings/weight", VALUES, "int8"), [("projection/weight", "embeddings/weight")]
    )
    np.testing.assert_array_equal(model.float32("projection/weight"), model.float32("embeddings/weight"))


def test_a_scalar_of_each_integer_type_is_an_integer(tmp_path: Path) -> None:
    model = _read(
        tmp_path,
        [
            ("a", "int8", np.array(-3, np.int8)),
            ("b", "int16", np.array(-1, np.int16)),
            ("c", "int32", np.array(70000, np.int32)),
        ],
    )
    assert [model.integer(name) for name in "abc"] == [-3, -1, 70000]


def _header(version: int = 6) -> bytes:
    spec = b"WhisperSpec\0"
    return struct.pack("<I", version) + struct.pack("<H", len(spec)) + spec + struct.pack("<I", 3)


def _one_variable(name: bytes, type_id: int = 0, size: int = 8, values: bytes = b"\0" * 8) -> bytes:
    named = struct.pack("<H", len(name)) + name
    return (
        _header()
        + struct.pack("<I", 1)
        + named
        + struct.pack("<BI", 1, 2)
        + struct.pack("<BI", type_id, size)
        + values
    )


WHOLE = model_bin_bytes([("w", "float32", VALUES)], [("v", "w")])


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"", "ends inside the binary version (byte 0 of 0): a truncated or not a CTranslate2 model.bin"),
        (
            WHOLE[:32],
            "ends inside the shape of w (byte 31 of 32): a truncated or not a CTranslate2 model.bin",
        ),
        (
            WHOLE[:60],
            "ends inside the values of w (byte 44 of 60): a truncated or not a CTranslate2 model.bin",
        ),
        (
            WHOLE[:-3],
            f"ends inside the variable of alias v (byte {len(WHOLE) - 4} of {len(WHOLE) - 3}): a truncated",
        ),
        (WHOLE + b"\0\0", "2 bytes after its last alias: not one whole CTranslate2 model.bin"),
        (
            _header(3),
            "binary version 3; CTranslate2's model.bin of versions 4 to 6 can be read (convert the model again "
            "with a recent CTranslate2)",
        ),
        (
            _one_variable(b"w\0", type_id=7),
            "variable w has data type 7; CTranslate2's are 0 float32, 1 int8, 2 int16, 3 int32, 4 float16, 5 bfloat16",
        ),
        (
            _one_variable(b"w\0", size=6, values=b"\0" * 6),
            "variable w holds 6 bytes; its shape [2] of float32 takes 8",
        ),
        (_one_variable(b"w"), "the name of variable 0 at byte 28 does not end in a NUL byte"),
        (_one_variable(b"\xff\0"), "the name of variable 0 at byte 28 is not UTF-8"),
        (
            model_bin_bytes([("w", "float32", VALUES)], [("v", "x")]),
            "alias v stands for x, which is no variable of the file",
        ),
    ],
    ids=[
        "empty",
        "in-shape",
        "in-values",
        "in-alias",
        "trailing",
        "version",
        "data-type",
        "size",
        "no-nul",
        "not-utf8",
        "alias-target",
    ],
)
def test_a_malformed_file_names_itself_and_what_is_wrong(tmp_path: Path, data: bytes, message: str) -> None:
    path = _write(tmp_path, data)
    with pytest.raises(ModelError) as error:
        read_model_bin(path)
    assert str(error.value).startswith(f"{path}: {message}")


def test_a_missing_file_says_it_cannot_be_read(tmp_path: Path) -> None:
    with pytest.raises(ModelError, match=r"model.bin: cannot read it: No such file or directory$"):
        read_model_bin(tmp_path / "model.bin")


def test_variables_it_cannot_use_as_asked_say_why(tmp_path: Path) -> None:
    model = _read(
        tmp_path,
        [
            ("q", "int8", np.ones((2, 2), np.int8)),
            ("r", "int8", np.ones((2, 2), np.int8)),
            ("r_scale", "float32", np.ones(3, np.float32)),
            ("f", "float32", VALUES),
        ],
    )
    path = tmp_path / "model.bin"
    messages = []
    for ask in (
        lambda: model.float32("q"),
        lambda: model.float32("r"),
        lambda: model.integer("f"),
        lambda: model.float32("z"),
    ):
        with pytest.raises(ModelError) as error:
            ask()
        messages.append(str(error.value))
    assert messages == [
        f"{path}: variable q is int8 without q_scale; a weight is float32, float16 or bfloat16, or int8 or int16 "
        "with its scale",
        f"{path}: r_scale has 3 values for r of shape [2, 2]: one, or one per row (2)",
        f"{path}: variable f is float32 of shape [3, 3]; a single integer expected",
        f"{path}: no variable z in this WhisperSpec model",
    ]


def test_a_variable_is_written_as_rank_shape_type_and_size_before_its_bytes() -> None:
    # the fixture's writer against the layout CTranslate2's model_spec.py documents
    assert variable_bytes("ab", "int16", np.array([1, 2], np.int16)) == (
        b"\x03\x00ab\x00"
        + b"\x01"
        + b"\x02\x00\x00\x00"
        + b"\x02"
        + b"\x04\x00\x00\x00"
        + b"\x01\x00\x02\x00"
    )

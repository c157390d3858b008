"""A Whisper model's weights as numpy arrays, float32, in openai-whisper's structure (the fused
projections as CTranslate2 stores them): what exporters/whisper_graphs.py builds the ONNX graphs
from, whatever file they were read from. No onnx here: reading a model needs none."""

from dataclasses import dataclass
from typing import Sequence

import numpy as np

LAYER_NORM_EPSILON = 1e-5  # torch.nn.LayerNorm's, whisper's


@dataclass(frozen=True)
class Dense:
    """A linear layer or a convolution: weight [out, in(, kernel)], as torch and CTranslate2 store
    it, and bias [out]."""

    weight: np.ndarray
    bias: np.ndarray


@dataclass(frozen=True)
class Norm:
    """A LayerNorm's scale (gamma) and shift (beta)."""

    gamma: np.ndarray
    beta: np.ndarray


@dataclass(frozen=True)
class EncoderBlock:
    """An encoder block: self-attention with query, key and value fused (rows q, k, v), and the MLP."""

    attention_norm: Norm
    qkv: Dense
    attention_out: Dense
    mlp_norm: Norm
    mlp_in: Dense
    mlp_out: Dense


@dataclass(frozen=True)
class DecoderBlock:
    """A decoder block: causal self-attention (q, k, v fused), cross-attention (k, v fused), the MLP."""

    attention_norm: Norm
    qkv: Dense
    attention_out: Dense
    cross_norm: Norm
    cross_query: Dense
    cross_kv: Dense
    cross_out: Dense
    mlp_norm: Norm
    mlp_in: Dense
    mlp_out: Dense


@dataclass(frozen=True)
class WhisperWeights:
    """A Whisper model's weights, float32, and its heads (the layers are the blocks listed)."""

    conv1: Dense
    conv2: Dense
    audio_positions: np.ndarray  # [audio positions, width]
    encoder_blocks: Sequence[EncoderBlock]
    encoder_norm: Norm
    encoder_heads: int
    embedding: np.ndarray  # [vocabulary, width]
    text_positions: np.ndarray  # [text context, width]
    decoder_blocks: Sequence[DecoderBlock]
    decoder_norm: Norm
    decoder_heads: int
    layer_norm_epsilon: float = LAYER_NORM_EPSILON

    @property
    def width(self) -> int:
        return int(self.embedding.shape[1])

    @property
    def mel_bands(self) -> int:
        return int(self.conv1.weight.shape[1])

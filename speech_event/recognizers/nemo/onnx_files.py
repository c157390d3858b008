"""The ONNX files of NeMo's exports: their names and the tensors each has (model.py runs them;
onnx_asr_layout.py reads a directory's files to tell its decoding).

A transducer (RNN-T or TDT) is two files:
``encoder-model.onnx``: ``audio_signal`` float32 [B, features, T] and ``length`` int64 [B] ->
``outputs`` [B, D, T'] and ``encoded_lengths`` [B].
``decoder_joint-model.onnx``: ``encoder_outputs`` [B, D, 1], ``targets`` int32 [B, 1],
``target_length`` int32 [B], ``input_states_1`` and ``input_states_2`` (LSTM h and c, [layers, B,
hidden]) -> ``outputs`` (logits, last dimension V + 1, then TDT's durations), ``prednet_lengths``,
``output_states_1``, ``output_states_2``.
A CTC model (or a hybrid model's CTC head) is one file, ``model.onnx``: ``audio_signal`` and
``length`` as above -> ``logprobs`` [B, T', V + 1].
Each file may have an int8 version (``encoder-model.int8.onnx``, onnx-asr's name): the ``quantization``
key picks it, and where only that one is there it is used (onnx/directory.py's Runtime).
"""

ENCODER_FILE = "encoder-model.onnx"
DECODER_JOINT_FILE = "decoder_joint-model.onnx"
CTC_FILE = "model.onnx"
NEMO_DIRECTORY = (
    f"a model directory holds {ENCODER_FILE}, {DECODER_JOINT_FILE} (a transducer) or {CTC_FILE} (CTC), "
    "vocab.txt and config.json (speech-event export-nemo MODEL.nemo DIR writes one)"
)
CTC_OUTPUTS = {"logprobs": 3}
ENCODER_INPUTS = {"audio_signal": 3, "length": 1}
ENCODER_OUTPUTS = {"outputs": 3, "encoded_lengths": 1}
DECODER_INPUTS = {
    "encoder_outputs": 3,
    "targets": 2,
    "target_length": 1,
    "input_states_1": 3,
    "input_states_2": 3,
}
DECODER_OUTPUTS = {"outputs": -1, "prednet_lengths": -1, "output_states_1": 3, "output_states_2": 3}

"""Whisper on onnxruntime: log-mel features -> encoder -> greedy decoding with Whisper's rules ->
byte tokens."""

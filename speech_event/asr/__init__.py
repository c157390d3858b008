"""The NeMo conformer-transducer engine: features, ONNX model, greedy decoding, vocabulary."""

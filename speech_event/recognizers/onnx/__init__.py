"""What the ONNX engine families share: the session, the model directory and its config.json,
mel filters, and the hypothesis that greedy decodings build."""

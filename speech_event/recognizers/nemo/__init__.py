"""The NeMo families (conformer-transducer, parakeet) on onnxruntime: features -> encoder ->
greedy decoding (RNN-T, TDT or CTC) -> vocabulary."""

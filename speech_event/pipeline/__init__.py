"""The node's pipeline, one module per step, in the order data flows.

``validate`` (a message becomes samples, or a named ``rejections`` entry) -> ``assembly`` (blocks
become utterances, cut at quiet points past the length limit) -> ``resample`` (to the engine's
rate) -> ``screen`` (what is not speech is never transcribed; ``vad`` is its voice detector) ->
``recognition_queue`` (closed utterances wait for the worker, bounded by max_backlog) ->
``transcript`` (what the engine said becomes the text published, or nothing).
"""

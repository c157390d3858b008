"""The node's pipeline, one module per step, in the order data flows.

1. ``validate``: a message becomes samples, or a rejection (counted and logged by ``rejections``).
2. ``assembly``: blocks become utterances, cut at quiet points past the length limit; when an
   utterance ends is the turn rules' (speech_event.turns), which hand each closed one on.
3. ``recognition_queue``, ``closed_utterances``: closed utterances wait for the ``worker``, bounded
   by max_backlog, and are recognized one at a time, each watched by the ``watchdog``.
4. ``resample``: to the engine's rate.
5. ``screen``: what is not speech is never transcribed (``vad`` is its voice detector).
6. ``recognition``: steps 4 and 5, then the engine, on the worker.
7. ``transcript``, ``publication``: what the engine said becomes the text published, or nothing;
   then the action's result, the statistics and the stored utterance (``storage``).
"""

"""The turn rules: when the utterance being collected ends, and what the recognition worker does
for it meanwhile. ``rules.TurnRules`` is the one entry the node calls (each block it accepts, each
change of what is in force); the timers and the worker's jobs call back into it.

- ``turn_taking``: the pause after the latest block ends the utterance (``speech_pause_period``,
  ``early_pause``), and the gap after it lets speculation start (``speculation_gap``);
- ``end_of_turn`` with ``speech_end``: the turn ends where the speech ended (``end_of_speech``)
  when the text up to there is complete; blocks that arrive meanwhile are held;
- ``smart_turn``: the turn-end model (``turn_end_model``), whether the audio says the turn is done;
- ``background_runs`` with ``speculation`` and ``partials``: speculations on the utterance so far
  and partial results, on the worker when it is idle.
"""

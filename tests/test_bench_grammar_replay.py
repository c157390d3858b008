"""bench/grammar.py --replay: a recorded run's neural decisions judged again with today's rule."""

import json
from pathlib import Path

import pytest

from bench.grammar import replay


def test_a_record_is_judged_again_by_todays_rule_and_pocketsphinx_lines_are_left_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = [
        # rejected when recorded (one word changed was the only misheard then): published now
        {
            "set": "tiny.en ked",
            "expected": "play some music",
            "published": "",
            "free": " Place a music",
            "free_score": -9.5,
            "scores": {"play some music": -9.2, "thank you": -12.0},
        },
        {
            "set": "tiny.en ked",
            "expected": None,
            "published": "",
            "free": " Thanks.",
            "free_score": -3.5,
            "scores": {"play some music": -20.0, "thank you": -3.0},
        },
        {"set": "pocketsphinx ked", "expected": "thank you", "published": "thank you", "ratio": -12.0},
    ]
    record = tmp_path / "grammar.jsonl"
    record.write_text("".join(json.dumps(line) + "\n" for line in lines))
    replay(record)
    assert capsys.readouterr().out == (
        "  tiny.en ked: commands (1) exact 100.0 %, rejected 0.0 %, as another 0.0 %; other speech (1) "
        "published 0.0 %; ratio min/median/max: commands 0.3 / 0.3 / 0.3, other 0.5 / 0.5 / 0.5\n"
    )

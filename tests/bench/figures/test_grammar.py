"""bench/figures/grammar.py --replay: a recorded run's neural decisions judged again with today's rule."""

import json
from pathlib import Path

import pytest

from bench.figures.grammar import replay


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
        # the evidence a Whisper run recorded is judged too: published on it, rejected without it
        {
            "set": "tiny.en kal",
            "expected": "wave your hand",
            "published": "wave your hand",
            "free": " Wait, go ahead.",
            "free_score": -5.6,
            "scores": {"wave your hand": -5.4, "thank you": -9.0},
            "evidence": {"wave your hand": 16.5},
        },
        {
            "set": "tiny.en kal",
            "expected": None,
            "published": "",
            "free": " Fadl Macar.",
            "free_score": -13.8,
            "scores": {"wave your hand": -20.0, "thank you": -7.6},
            "evidence": {"thank you": -3.1},
        },
        {"set": "pocketsphinx ked", "expected": "thank you", "published": "thank you", "ratio": -12.0},
    ]
    record = tmp_path / "grammar.jsonl"
    record.write_text("".join(json.dumps(line) + "\n" for line in lines))
    replay(record)
    assert capsys.readouterr().out == (
        "  tiny.en ked: commands (1) exact 100.0 %, rejected 0.0 %, as another 0.0 %; other speech (1) "
        "published 0.0 %; ratio min/median/max: commands 0.3 / 0.3 / 0.3, other 0.5 / 0.5 / 0.5\n"
        "  tiny.en kal: commands (1) exact 100.0 %, rejected 0.0 %, as another 0.0 %; other speech (1) "
        "published 0.0 %; ratio min/median/max: commands 0.2 / 0.2 / 0.2, other 6.2 / 6.2 / 6.2\n"
    )

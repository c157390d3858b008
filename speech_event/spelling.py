"""How texts are spelt for what reads them: a grammar's phrases (``spelt``) and the robot's
Behaviour Controller (``robot_written``), which looks for lower-case words such as "yes" in the text
as the robot's NeMo model writes it. Whisper writes capitals, punctuation and numbers in digits
(" Yes.", "10 of clubs."), which neither would find."""

import re

_NOT_SPELT = re.compile(r"[^a-z' ]+")
# Neither a letter of any alphabet, nor an apostrophe, nor a space (digits are words by then).
_NOT_WRITTEN = re.compile(r"[^\w' ]|[\d_]")
_NUMBER = re.compile(r"\d+")
_THOUSANDS_COMMA = re.compile(r"(?<=\d),(?=\d{3}\b)")
_ONES = [
    "zero",
    "one",
    "two",
    "three",
    "four",
    "five",
    "six",
    "seven",
    "eight",
    "nine",
    "ten",
    "eleven",
    "twelve",
    "thirteen",
    "fourteen",
    "fifteen",
    "sixteen",
    "seventeen",
    "eighteen",
    "nineteen",
]
_TENS = ["-", "-", "twenty", "thirty", "forty", "fifty", "sixty", "seventy", "eighty", "ninety"]


def number_words(number: int) -> str:
    """``number`` in words as a grammar spells it (1234: "one thousand two hundred thirty four");
    from a million on, digit by digit."""
    if number < 20:
        return _ONES[number]
    if number < 100:
        return " ".join([_TENS[number // 10]] + ([_ONES[number % 10]] if number % 10 else []))
    if number < 1000:
        rest = [number_words(number % 100)] if number % 100 else []
        return " ".join([_ONES[number // 100], "hundred", *rest])
    if number < 1_000_000:
        rest = [number_words(number % 1000)] if number % 1000 else []
        return " ".join([number_words(number // 1000), "thousand", *rest])
    return " ".join(_ONES[int(digit)] for digit in str(number))


def spelt(text: str) -> str:
    """``text`` as a grammar writes phrases: lower-case words of a-z and ', punctuation dropped,
    numbers in words. Whisper writes numbers in digits ("10 of clubs." for the cards recording of
    "ten of clubs"), which a grammar of words would otherwise never match."""
    return " ".join(_NOT_SPELT.sub(" ", _numbers_in_words(text).lower()).split())


def robot_written(text: str) -> str:
    """``text`` as the robot's NeMo model writes: lower case, numbers in words, no punctuation but
    the apostrophes inside words ("i'm"), single spaces, nothing around; letters of any alphabet
    kept ("café")."""
    words = (word.strip("'") for word in _NOT_WRITTEN.sub(" ", _numbers_in_words(text).lower()).split())
    return " ".join(word for word in words if word)


def _numbers_in_words(text: str) -> str:
    """``text`` with each number in words, set apart by spaces ("1,250" and "10" too)."""
    return _NUMBER.sub(
        lambda digits: f" {number_words(int(digits.group()))} ", _THOUSANDS_COMMA.sub("", text)
    )

"""Intake takes any text: for whatever a generator or a file holds (any characters, lone
surrogates, NULs and control characters included, and broken variants of a good answer),
`read_program` returns a checked program or says why there is none (`Unusable`,
`ForbiddenProgram`), and never raises anything else. Hypothesis generates the texts; the
examples are bounded so that the whole file takes well under a minute."""

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from colmo.generate.base import Generation
from colmo.intake import Unusable, read_program
from colmo.sandbox.check import ForbiddenProgram

ALLOWED = ("numpy", "math")
GOOD = "```python\nimport numpy as np\n\ndef policy(obs):\n    theta = np.arctan2(obs[1], obs[0])\n    return -2.0 * theta - 0.5 * obs[2]\n```"
ANY_CHARACTER = st.characters(codec=None, exclude_categories=())  # surrogates, NUL, controls: everything
FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def read(text: str) -> None:
    try:
        read_program(Generation(text, "fuzz").text, ALLOWED)
    except (Unusable, ForbiddenProgram):
        pass


@FUZZ
@given(st.text(ANY_CHARACTER, max_size=300))
def test_any_text_is_read_or_refused(text):
    read(text)


@FUZZ
@given(st.integers(0, len(GOOD)), st.integers(0, 20), st.text(ANY_CHARACTER, max_size=8))
def test_a_good_answer_broken_anywhere_is_read_or_refused(start, cut, inserted):
    read(GOOD[:start] + inserted + GOOD[start + cut:])


@FUZZ
@given(st.text(st.sampled_from("()[]{}:=+-*/.,'\"\\#\n\t 0123456789abdefilnoprstuvxy_@\x00\ufffd\ud800"), max_size=400))
def test_code_like_text_is_read_or_refused(text):
    read("def policy(obs):\n" + text)


def test_the_good_answer_reads():
    assert read_program(GOOD, ALLOWED).n_params == 2

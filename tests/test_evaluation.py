"""The evaluator's requests (`colmo.evaluation.Evaluator`): a program's episodes split into
chunks, one request each, as both the tuning and the simplifier's referee scores spread them."""

from __future__ import annotations

import pytest

from colmo.evaluation import Evaluator


def evaluator(seeds: tuple[int, ...]) -> Evaluator:
    return Evaluator("spec.py", (), seeds, (), 1.0, 1.0, 256)


@pytest.mark.parametrize(
    "parts, chunks",
    [
        (1, [(11, 12, 13, 14, 15)]),
        (2, [(11, 12, 13), (14, 15)]),  # near-equal, in order
        (5, [(11,), (12,), (13,), (14,), (15,)]),
        (9, [(11,), (12,), (13,), (14,), (15,)]),  # at most one seed a chunk
        (0, [(11, 12, 13, 14, 15)]),  # at least one chunk
    ],
)
def test_seed_chunks_cover_the_seeds_in_order(parts, chunks):
    assert evaluator((11, 12, 13, 14, 15)).seed_chunks(parts) == chunks


@pytest.mark.parametrize("returns, expected", [
    ((189.1, 189.1, 189.1), True),  # an upright start every episode
    ((1e6, 1e6 + 1e-4), True),  # equal up to float noise
    ((189.1, 159.3), False),
    ((189.1,), False),  # one episode tells nothing
    ((), False),
    (None, False),  # a program that was not scored
])
def test_training_episodes_that_all_returned_the_same_are_told_apart(returns, expected):
    from colmo.heldout import alike

    assert alike(returns) is expected

"""The program probe: does a program run on its task at all?

It runs the first `steps` control steps of one episode in a sandbox worker of its own (so
probes never wait behind evaluations, and programs never run in the coordinator), and passes
a program that returns valid actions there. Generators that want one (`wants_probe`) use it to
offer only programs that work: the embedded `mutate` generator redraws children that fail it.
"""

from __future__ import annotations

from colmo.evaluation import Evaluator
from colmo.executor import LocalExecutor
from colmo.program import ProgramError, parametrize


class ProgramProbe:
    def __init__(self, evaluator: Evaluator, steps: int = 20):
        self.executor = LocalExecutor(1, evaluator.memory_mb)
        self.evaluator = evaluator
        self.steps = steps

    def __call__(self, code: str) -> bool:
        try:
            program = parametrize(code)
        except ProgramError:
            return False
        request = self.evaluator.request(program.skeleton, program.values, seeds=self.evaluator.seeds[:1], steps=self.steps)
        return self.executor.evaluate([request])[0].failure is None

    def close(self) -> None:
        self.executor.close()

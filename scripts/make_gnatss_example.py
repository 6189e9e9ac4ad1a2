"""Regenerate the packaged synthetic GNATSS-format survey (``src/oceanloc/data/gnatss_synthetic``).

Usage: ``python scripts/make_gnatss_example.py [FOLDER]`` (default: the package's data folder). Writes
every input file of :func:`oceanloc.sim.gnatss_survey.write_gnatss_survey` for
:data:`~oceanloc.sim.gnatss_survey.EXAMPLE_SPEC` (seed 2026), deterministic: the same bytes each run.
The folder's README.md, LICENSE and __init__.py are not touched.
"""

from __future__ import annotations

import sys
from pathlib import Path

from oceanloc.sim.gnatss_survey import EXAMPLE_SPEC, write_gnatss_survey


def main(argv: list[str]) -> int:
    default = Path(__file__).resolve().parents[1] / "src" / "oceanloc" / "data" / "gnatss_synthetic"
    folder = Path(argv[0]) if argv else default
    _, files = write_gnatss_survey(EXAMPLE_SPEC, folder, relative=True)
    print(f"wrote the synthetic GNATSS-format survey to {files.folder}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))

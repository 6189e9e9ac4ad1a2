"""Run the benchmarks: ``python benchmarks/run.py [NAME ...]``.

Each ``benchmarks/bench_<name>.py`` has a ``main()`` that prints its measured figures beside their
targets. With names, only those benchmarks run.
"""

from __future__ import annotations

import importlib.util
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(names: list[str]) -> int:
    files = sorted(HERE.glob("bench_*.py"))
    if names:
        files = [f for f in files if f.stem.removeprefix("bench_") in names]
        if not files:
            print(f"no benchmark named {', '.join(names)}", file=sys.stderr)
            return 2
    for path in files:
        spec = importlib.util.spec_from_file_location(path.stem, path)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        print(f"\n=== {path.stem.removeprefix('bench_')} ===", flush=True)
        start = time.perf_counter()
        module.main()
        print(f"({time.perf_counter() - start:.1f} s)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

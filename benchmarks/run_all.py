"""Run every ``benchmarks/bench_*.py`` and print one table (``make bench``).

Each benchmark module defines ``benchmarks() -> list[dict]``; a row has ``name``,
``value``, ``unit`` and optionally ``target`` (text such as ">= 2e7") and ``ok`` (bool).
Pass module names (e.g. ``halfspace``) to run a subset.
"""

from __future__ import annotations

import importlib.util
import json
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(argv: list[str]) -> int:
    wanted = set(argv)
    rows = []
    for path in sorted(HERE.glob("bench_*.py")):
        short = path.stem.removeprefix("bench_")
        if wanted and short not in wanted:
            continue
        spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        t0 = time.perf_counter()
        print(f"running {path.name} ...", file=sys.stderr, flush=True)
        for row in module.benchmarks():
            rows.append({"suite": short, **row})
        print(f"  {path.name}: {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
    header = f"{'suite':<10} {'benchmark':<58} {'value':>12} {'unit':<16} {'target':<12} ok"
    print(header)
    print("-" * len(header))
    for r in rows:
        ok = r.get("ok")
        # a row without a target is a measurement, not a check: nothing to pass
        mark = "-" if r.get("target") is None else ("" if ok is None else
                                                    ("yes" if ok else "NO"))
        print(f"{r['suite']:<10} {r['name']:<58} {r['value']:>12.4g} {r['unit']:<16} "
              f"{str(r.get('target', '')):<12} {mark}")
    out = HERE.parent / "bench-results"
    out.mkdir(exist_ok=True)
    (out / "latest.json").write_text(json.dumps(rows, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

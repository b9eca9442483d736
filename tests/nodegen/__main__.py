"""Write generated right lab nodes (and their mutants) to a folder: ``python -m tests.nodegen --seed N --out DIR``.

Each node is ``<out>/genNNN_X.py`` (X its choice); with ``--mutants`` each mistake is ``genNNN_X__<mistake>.py``
beside it; ``knobs.json`` lists every file's knobs and, for a mutant, what the grader must fail it for.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path

if __package__ in (None, ""):  # run as a file (python tests/nodegen/__main__.py): the repository on the path
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from tests.nodegen import BY_LIDAR, EXPECT, generate, mutants  # noqa: E402


def main(argv: Sequence[str] | None = None) -> int:
    """Write ``--count`` nodes from ``--seed`` on; print one line per file."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="the first seed")
    parser.add_argument("--count", type=int, default=1, help="how many nodes (seeds seed..seed+count-1)")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--mutants", action="store_true", help="also write each node's mutants")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    listing = {}
    for seed in range(args.seed, args.seed + args.count):
        spec = generate(seed)
        path = args.out / f"{spec.name}.py"
        path.write_text(spec.source)
        listing[path.name] = {"seed": seed, "knobs": asdict(spec.knobs), "mistake": None}
        print(path)
        for mistake, source in (mutants(spec) if args.mutants else {}).items():
            wrong = args.out / f"{spec.name}__{mistake}.py"
            wrong.write_text(source)
            pattern, cells = EXPECT[mistake][spec.knobs.choice]
            listing[wrong.name] = {"seed": seed, "knobs": asdict(spec.knobs), "mistake": mistake,
                                   "reason": pattern, "cells": cells, "by_lidar": BY_LIDAR.get(mistake)}
            print(wrong)
    (args.out / "knobs.json").write_text(json.dumps(listing, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

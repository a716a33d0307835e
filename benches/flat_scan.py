"""Which validation parts of the realdata records ``sysid.compare`` calls flat (issue 26):
``sysid.validation.fit.flat_outputs`` on every record's validation part with the estimation
means removed (as ``benches/realdata.py`` compares), under the default and reversed splits.

    PYTHONPATH=python .venv/bin/python benches/flat_scan.py --unshipped /tmp/daisy2 \\
        --more-records DIR --fresh-records DIR --fresh2-records DIR
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import realdata as rd  # noqa: E402


def main() -> None:
    from sysid.validation.fit import flat_outputs

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    rd.add_record_options(ap)
    args = ap.parse_args()
    loads = rd.record_loaders(args)
    for split in ("default", "reversed"):
        rd.SPLIT = split
        hits = []
        for name, load in loads.items():
            (ue, ye), (uv, yv) = load()
            mu, my = ue.mean(0), ye.mean(0)
            hits += [f"{name} output {j}: {why}" for j, why in flat_outputs(uv - mu, yv - my)]
        print(f"{split}: {len(loads)} records, flat: " + ("; ".join(hits) or "none"))


if __name__ == "__main__":
    main()

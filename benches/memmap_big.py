"""Out-of-core run: N samples (default 10^8) of 2 inputs and 2 outputs read from a memmap.

    python benches/memmap_big.py [--n 100000000] [--horizon 20] [--keep]

Writes the record to benches/.data/big.npy (N x 4 doubles: 3.2 GB at N = 10^8; check
`df -h` first), then, each in a fresh process: one sequential read of the file (the I/O
floor), and the compression by `sysid.compress_stream` with both compressors, reporting wall
time and peak resident memory, and the pole error of the identified model. Deletes the file
unless --keep.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

CHILD = r"""
import json, resource, sys, time
import numpy as np
mode, path, horizon, order = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
z = np.load(path, mmap_mode="r")
t0 = time.perf_counter()
out = {"mode": mode}
if mode == "read":
    s = 0.0
    for a in range(0, z.shape[0], 1 << 20):
        s += float(np.asarray(z[a:a + (1 << 20)]).sum())
        from sysid.subspace.streaming import _release_pages
        _release_pages(z, a, min(z.shape[0], a + (1 << 20)))
else:
    import sysid
    f = sysid.compress_stream((z[:, :2], z[:, 2:]), horizon, compressor=mode, progress=False)
    out["compress_seconds"] = time.perf_counter() - t0
    out["source"] = f.source
    model = sysid.SubspaceEstimator.from_factor(f, dt=1.0).fit(order=order)
    out["poles"] = [[float(p.real), float(p.imag)] for p in np.asarray(model.poles())]
out["seconds"] = time.perf_counter() - t0
out["peak_mb"] = [int(x.split()[1]) / 1024 for x in open("/proc/self/status")
                  if x.startswith("VmHWM:")][0]
print(json.dumps(out))
"""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=10**8)
    ap.add_argument("--horizon", type=int, default=20)
    ap.add_argument("--order", type=int, default=4)
    ap.add_argument("--keep", action="store_true")
    ap.add_argument("--compressors", nargs="*", default=["correlation", "qr"])
    args = ap.parse_args()
    sys.path.insert(0, str(HERE))
    from data import generate
    from run import pole_error

    (HERE / ".data").mkdir(exist_ok=True)
    path = HERE / ".data" / "big.npy"
    t0 = time.perf_counter()
    true = generate(path, args.n, 2, 2, args.order, seed=7)
    print(f"generated {path} ({path.stat().st_size / 1e9:.2f} GB) in "
          f"{time.perf_counter() - t0:.0f} s", file=sys.stderr)
    env = {"PYTHONPATH": f"{ROOT / 'python'}:{HERE}", "PATH": "/usr/bin:/bin"}
    results = []
    try:
        for mode in ["read", *args.compressors]:
            r = subprocess.run(
                [sys.executable, "-c", CHILD, mode, str(path), str(args.horizon),
                 str(args.order)],
                capture_output=True, text=True, env=env,
            )
            if r.returncode != 0:
                results.append({"mode": mode, "error": r.stderr.strip().splitlines()[-1]})
            else:
                res = json.loads(r.stdout.strip().splitlines()[-1])
                if "poles" in res:
                    res["pole_error"] = pole_error(res.pop("poles"), true)
                results.append(res)
            print(json.dumps(results[-1]), flush=True)
    finally:
        if not args.keep:
            path.unlink(missing_ok=True)
    out = HERE / "results" / "memmap_big.json"
    out.write_text(json.dumps({"n": args.n, "horizon": args.horizon, "results": results},
                              indent=1))


if __name__ == "__main__":
    main()

"""Cost per sample of `sysid.RecursiveSubspace` updates over a 10^6-sample stream.

The stream is processed in chunks; the time of each chunk's update (factor update plus the
model fit) is recorded, and the cost per sample is compared between the first and the last
tenth of the stream: it must not grow with the amount of data seen.

Run:  .venv/bin/python benches/recursive_subspace.py [--samples 1000000] [--chunk 10000]
Result: benches/results/recursive_subspace.md
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

import sysid


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--chunk", type=int, default=10_000)
    ap.add_argument("--horizon", type=int, default=10)
    ap.add_argument("--forgetting", type=float, default=0.9999)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    true = sysid.StateSpaceModel([[0.8, 0.2], [-0.2, 0.7]], [[1.0], [0.5]], [[1.0, 0.0]])
    n = args.samples
    u = rng.standard_normal(n)
    y = true.simulate(u) + 0.1 * rng.standard_normal((n, 1))
    rs = sysid.RecursiveSubspace(order=2, horizon=args.horizon, forgetting=args.forgetting)
    per_sample = []
    for k in range(0, n, args.chunk):
        t0 = time.perf_counter()
        model = rs.update(u[k:k + args.chunk], y[k:k + args.chunk])
        per_sample.append((time.perf_counter() - t0) / args.chunk)
    tenth = max(1, len(per_sample) // 10)
    first, last = np.median(per_sample[:tenth]), np.median(per_sample[-tenth:])
    print(f"{n} samples, chunks of {args.chunk}, horizon {args.horizon}, "
          f"forgetting {args.forgetting}, {platform.processor() or platform.machine()}")
    print(f"cost per sample: first tenth {first * 1e6:.3f} us, last tenth {last * 1e6:.3f} us, "
          f"ratio {last / first:.2f}")
    print(f"total {np.sum(per_sample) * args.chunk:.2f} s; final poles "
          f"{np.round(np.sort_complex(model.poles()), 4)}")


if __name__ == "__main__":
    main()

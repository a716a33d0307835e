"""The ``sysid`` command line.

``sysid demo`` identifies the bundled hair-dryer record (the quickstart's main job).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

import numpy as np

__all__ = ["main"]


def _demo(args: argparse.Namespace) -> int:
    from . import datasets
    from .data import IOData
    from .subspace import SubspaceEstimator

    data = datasets.load_dryer()
    print(data)
    u, y = data.u, data.y
    est_data = IOData(u=u[:500], y=y[:500], dt=data.dt)
    est = SubspaceEstimator(est_data, horizon=15)
    print(est)
    sv = est.singular_values
    print("singular values:", np.array2string(sv, precision=4, max_line_width=100))
    model = est.fit(order="auto", x0=True)
    print(model)
    print("poles:", np.array2string(model.poles(), precision=4))
    yv, uv = y[500:], u[500:]
    for name, yh in (
        ("simulation", model.simulate(uv)),
        ("1-step prediction", model.predict(uv, yv)),
    ):
        # NRMSE fit after removing the transient-independent offset of the validation part
        e = yv - yh
        fit = 100 * (1 - np.linalg.norm(e - e.mean(0)) / np.linalg.norm(yv - yv.mean(0)))
        print(f"validation fit ({name}, samples 501-1000, offset removed): {fit:.1f} %")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``sysid`` command."""
    parser = argparse.ArgumentParser(prog="sysid", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="identify the bundled hair-dryer record")
    demo.set_defaults(func=_demo)
    args = parser.parse_args(argv)
    return int(args.func(args))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""``sysid demo``: the pipeline on the bundled hair-dryer record."""

from __future__ import annotations

import argparse

from ..data.iodata import IOData
from .pipeline import _check_report_dir, _print_summary, identify
from .progress import _Progress


def _demo(args: argparse.Namespace) -> int:
    from ..data import datasets

    _check_report_dir(args.report)
    data = datasets.load_dryer()
    print(data)
    u, y = data.u, data.y
    kw = {"dt": data.dt, "input_names": data.input_names, "output_names": data.output_names}
    est_data = IOData(u=u[:500], y=y[:500], **kw)
    val_data = IOData(u=u[500:], y=y[500:], **kw)
    print("estimation: samples 1-500, validation: samples 501-1000, horizon 15")
    out = identify(est_data, val_data, order="auto", horizon=15, report=args.report,
                   preprocessing={"samples": "estimation 1-500, validation 501-1000",
                                  "detrend": "none (raw data, as SLICOT)"},
                   progress=_Progress(args.quiet), uncertainty="bootstrap")
    _print_summary(out)
    return 0

